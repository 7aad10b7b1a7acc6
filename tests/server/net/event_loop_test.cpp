// The reactor: descriptors' handlers, coalesced wake-ups from other threads, calls onto the loop.
#include "net/event_loop.hpp"

#include <gtest/gtest.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <future>
#include <thread>
#include <vector>

namespace uavsim::server::net {
namespace {

TEST(EventLoop, AReadableDescriptorRunsItsHandlerOnTheLoopThread) {
  int pair[2];
  ASSERT_EQ(socketpair(AF_UNIX, SOCK_STREAM | SOCK_NONBLOCK, 0, pair), 0);
  EventLoop loop;
  std::promise<bool> on_loop;
  loop.watch(pair[0], EPOLLIN, [&](std::uint32_t events) {
    char byte = 0;
    ASSERT_EQ(read(pair[0], &byte, 1), 1);  // level-triggered: read it, or the handler runs again
    EXPECT_TRUE(events & EPOLLIN);
    on_loop.set_value(loop.in_io_thread());
  });
  loop.start();
  ASSERT_EQ(write(pair[1], "x", 1), 1);
  EXPECT_TRUE(on_loop.get_future().get());
  EXPECT_FALSE(loop.in_io_thread());
  loop.stop();
  close(pair[0]);
  close(pair[1]);
}

TEST(EventLoop, WakeUpsBeforeTheLoopGetsToThemAreServedOnce) {
  EventLoop loop;
  int served = 0;  // I/O thread
  Waker& waker = loop.make_waker([&] { ++served; });
  for (int k = 0; k < 3; ++k) waker.wake();
  loop.start();
  // call() runs after the wake-ups made before it
  int seen = -1;
  loop.call([&] { seen = served; });
  EXPECT_EQ(seen, 1);
}

TEST(EventLoop, AWakeUpFromAnotherThreadIsServedBeforeALaterCall) {
  EventLoop loop;
  int served = 0;
  Waker& a = loop.make_waker([&] { ++served; });
  Waker& b = loop.make_waker([&] { served += 10; });
  loop.start();
  for (int round = 1; round <= 50; ++round) {
    std::thread([&] { a.wake(); }).join();
    int seen = -1;
    loop.call([&] { seen = served; });
    ASSERT_EQ(seen, round);  // b was never woken
  }
  b.wake();
  int seen = -1;
  loop.call([&] { seen = served; });
  EXPECT_EQ(seen, 60);
}

// producers on several threads queue work and wake; the loop must see every item without any later
// wake-up to rescue a lost one (the future would time out)
TEST(EventLoop, NoWakeUpIsLostUnderContention) {
  constexpr int kThreads = 4;
  constexpr int kItemsPerThread = 20000;
  EventLoop loop;
  std::atomic<int> queued{0};
  int drained = 0;  // I/O thread
  std::promise<void> all;
  Waker* waker = nullptr;
  waker = &loop.make_waker([&] {
    const int now = queued.load();
    if (drained < now && now == kThreads * kItemsPerThread) all.set_value();
    drained = now;
  });
  loop.start();
  std::vector<std::thread> producers;
  for (int t = 0; t < kThreads; ++t) {
    producers.emplace_back([&] {
      for (int k = 0; k < kItemsPerThread; ++k) {
        queued.fetch_add(1);
        waker->wake();
      }
    });
  }
  for (auto& p : producers) p.join();
  EXPECT_EQ(all.get_future().wait_for(std::chrono::seconds(30)), std::future_status::ready);
  loop.stop();
}

TEST(EventLoop, CallRunsInlineWhenTheLoopIsNotRunning) {
  EventLoop loop;
  std::thread::id ran_on;
  loop.call([&] { ran_on = std::this_thread::get_id(); });
  EXPECT_EQ(ran_on, std::this_thread::get_id());
  loop.start();
  loop.call([&] { ran_on = std::this_thread::get_id(); });
  EXPECT_NE(ran_on, std::this_thread::get_id());
  loop.stop();
  loop.call([&] { ran_on = std::this_thread::get_id(); });
  EXPECT_EQ(ran_on, std::this_thread::get_id());
}

// a handler that closes another descriptor of the same pass, whose number is then reused: the event
// of the old descriptor must not reach the new one's handler
TEST(EventLoop, AnUnwatchedDescriptorsPendingEventIsSkipped) {
  int first[2], second[2];
  ASSERT_EQ(socketpair(AF_UNIX, SOCK_STREAM | SOCK_NONBLOCK, 0, first), 0);
  ASSERT_EQ(socketpair(AF_UNIX, SOCK_STREAM | SOCK_NONBLOCK, 0, second), 0);
  // both readable before the loop's first wait: one pass sees both
  ASSERT_EQ(write(first[1], "x", 1), 1);
  ASSERT_EQ(write(second[1], "x", 1), 1);
  EventLoop loop;
  int handled = 0;  // I/O thread
  int reused = -1;
  bool reused_called = false;
  auto closer = [&](int mine, int other) {
    return [&, mine, other](std::uint32_t) {
      ++handled;
      char byte = 0;
      [[maybe_unused]] const auto n = read(mine, &byte, 1);
      if (reused >= 0) return;
      // close the other one and give its number to a fresh descriptor (lowest free number)
      loop.unwatch(other);
      close(other);
      reused = dup(mine);
      ASSERT_EQ(reused, other);
      loop.watch(reused, EPOLLIN, [&](std::uint32_t) { reused_called = true; });
    };
  };
  loop.watch(first[0], EPOLLIN, closer(first[0], second[0]));
  loop.watch(second[0], EPOLLIN, closer(second[0], first[0]));
  loop.start();
  loop.call([] {});
  int seen = -1;
  loop.call([&] { seen = handled; });
  EXPECT_EQ(seen, 1);
  loop.stop();
  // the dup shares the drained socket: nothing to read, so its handler never ran legitimately
  // either
  EXPECT_FALSE(reused_called);
  close(first[0] == reused ? second[0] : first[0]);
  close(reused);
  close(first[1]);
  close(second[1]);
}

}  // namespace
}  // namespace uavsim::server::net
