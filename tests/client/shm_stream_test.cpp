// The sim API's shared-memory stream (docs/protocol.md, "Shared-memory stream") against the real
// server in process: the op's ranges, a client that breaks its ring and one killed while it holds a
// tick are dropped and the server goes on with the others, as on TCP. (Runs on both transports:
// system_test.cpp's ClientDeterminism.SharedMemoryAndTcpGiveTheSameRun.)
#include "shm_stream.hpp"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <poll.h>
#include <signal.h>
#include <sys/mman.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <string>
#include <vector>

#include "loop_services.hpp"
#include "net.hpp"
#include "raw_shm_client.hpp"
#include "sim_channel.hpp"
#include "sim_harness.hpp"
#include "uavsim/client/event_loop.hpp"
#include "uavsim/common/shm_ring.hpp"

namespace uavsim::client::testing {
namespace {

TEST(SharedMemoryStream, TheOpChecksItsRangesAndIsOfferedOnce) {
  SimServer server;
  RawShmClient c(server.api_port());
  for (const Json bad : {Json(1000), Json(65537), Json(-65536), Json(1u << 29), Json("big")}) {
    const Json r = c.tcp_request({{"op", "lockstep_shm"}, {"ring_bytes", bad}});
    EXPECT_EQ(r["ok"], false) << bad;
    EXPECT_EQ(r["error"]["code"], "bad_field") << r;
  }
  const Json offer = c.tcp_request({{"op", "lockstep_shm"}, {"ring_bytes", 65536}});
  ASSERT_EQ(offer["ok"], true) << offer;
  EXPECT_EQ(offer["result"]["ring_bytes"], 65536);
  ASSERT_TRUE(c.take_stream(offer["result"]));
  // the names are gone once mapped: nobody else opens them
  const std::string name = common::shm::object_name(offer["result"]["token"].get<std::string>());
  EXPECT_LT(shm_open(name.c_str(), O_RDWR, 0), 0);
  // a second offer is refused, its reply on the stream
  c.send({{"op", "lockstep_shm"}, {"id", 7}});
  common::shm::RingReader::Record rec;
  ASSERT_TRUE(c.next(&rec));
  ASSERT_EQ(rec.type, common::shm::RecordType::kStream);
  const Json again =
      Json::parse(std::string(rec.payload.begin(), rec.payload.end()), nullptr, false);
  EXPECT_EQ(again["id"], 7);
  EXPECT_EQ(again["error"]["code"], "bad_state") << again;
}

// A client that moves its ring's read position past what the server wrote is dropped at the
// server's next write (here the reply to its `done`); the other lockstep client ticks on.
TEST(SharedMemoryStream, AClientThatBreaksItsRingIsDroppedAndTheOthersTickOn) {
  SimServer server;
  auto l = EventLoop::create(LoopConfig::lockstep("127.0.0.1", server.api_port(), 0.02));
  ASSERT_TRUE(l) << l.message();
  ASSERT_TRUE(LoopServices(**l).sim_channel()->on_ring());
  RawShmClient hostile(server.api_port());
  const Json offer = hostile.tcp_request({{"op", "lockstep_shm"}});
  ASSERT_EQ(offer["ok"], true) << offer;
  ASSERT_TRUE(hostile.take_stream(offer["result"]));
  hostile.send({{"op", "lockstep_join"}, {"period_s", 0.02}});
  // the join's reply on its stream: the server has served the join (at its next gate)
  common::shm::RingReader::Record rec;
  ASSERT_TRUE(hostile.next(&rec));
  ASSERT_EQ(rec.type, common::shm::RecordType::kStream);
  const Json joined =
      Json::parse(std::string(rec.payload.begin(), rec.payload.end()), nullptr, false);
  ASSERT_EQ(joined.value("ok", false), true) << joined;
  ApiClient api(server.api_port());
  ASSERT_EQ(api.request({{"op", "status"}})["result"]["lockstep_clients"], 2);
  ASSERT_EQ(api.request({{"op", "resume"}}).value("ok", false), true);
  // its first tick, as a binary record
  bool ticked = false;
  while (!ticked && hostile.next(&rec)) ticked = rec.type == common::shm::RecordType::kTick;
  ASSERT_TRUE(ticked);
  std::string why;
  const auto tick = common::shm::decode_tick(rec.payload, &why);
  ASSERT_TRUE(tick) << why;
  // garbage where its read position is, then done
  hostile.header()->tail += 1u << 20;
  hostile.send({{"op", "done"}, {"tick", tick->tick}});
  EXPECT_TRUE(hostile.hung_up());
  // the server dropped it and goes on with the good client
  EventLoop& loop = **l;
  const double before = loop.now();
  ASSERT_TRUE(loop.run_for(1.0));
  EXPECT_GE(loop.now(), before + 1.0 - 1e-9);
  EXPECT_EQ(api.request({{"op", "status"}})["result"]["lockstep_clients"], 1);
}

// A lockstep client on the shared-memory stream, killed (SIGKILL) while it holds a tick: its
// connection closes, it leaves the lockstep, and the clock goes on, with no lockstep timeout. The
// client is forked before the server starts (no threads to copy).
TEST(SharedMemoryStream, AClientKilledHoldingItsTickIsDroppedAndTheClockGoesOn) {
  int to_child[2], from_child[2];
  ASSERT_EQ(pipe(to_child), 0);
  ASSERT_EQ(pipe(from_child), 0);
  const pid_t child = fork();
  if (child == 0) {
    prctl(PR_SET_PDEATHSIG, SIGKILL);  // never outlives the test
    int port = 0;
    if (read(to_child[0], &port, sizeof(port)) != sizeof(port)) _exit(2);
    auto loop = EventLoop::create(LoopConfig::lockstep("127.0.0.1", port, 0.02));
    const char joined = loop && LoopServices(**loop).sim_channel()->on_ring() ? 'r' : 't';
    (void)!write(from_child[1], &joined, 1);
    pause();  // holds its first tick until killed
    _exit(0);
  }
  close(to_child[0]);
  close(from_child[1]);
  SimServer
      server;  // (its lockstep timeout is 30 s: only the disconnect can free the clock in time)
  ApiClient api(server.api_port());
  const int port = server.api_port();
  ASSERT_EQ(write(to_child[1], &port, sizeof(port)), static_cast<ssize_t>(sizeof(port)));
  char joined = 0;
  ASSERT_EQ(read(from_child[0], &joined, 1), 1);
  EXPECT_EQ(joined, 'r');
  ASSERT_EQ(api.request({{"op", "resume"}}).value("ok", false), true);
  // held at its first tick
  const double held = api.request({{"op", "status"}})["result"]["time_s"];
  EXPECT_EQ(api.request({{"op", "status"}})["result"]["time_s"], held);
  ASSERT_EQ(kill(child, SIGKILL), 0);
  ASSERT_EQ(waitpid(child, nullptr, 0), child);
  // a step of 0.1 s is answered once its steps have run, which needs the killed client out of the
  // lockstep: the reply is the wait (its 10 s request timeout, well under the 30 s lockstep
  // timeout, turns a clock still held into a failure, not a hang)
  const Json stepped = api.request({{"op", "step"}, {"duration_s", 0.1}});
  ASSERT_EQ(stepped.value("ok", false), true) << stepped;
  EXPECT_GE(stepped["result"].value("time_s", 0.0), held + 0.1 - 1e-9);
  EXPECT_EQ(api.request({{"op", "status"}})["result"]["lockstep_clients"], 0);
  close(to_child[1]);
  close(from_child[0]);
}

using Lines = std::vector<std::string>;

// A raw lockstep client on its ring (period 20 ms) at sim time 0: one wake-up brings its join's
// reply and its first tick (a paused server announces the tick it is held at), number 0.
void join_on_ring(RawShmClient& c) {
  const Json offer = c.tcp_request({{"op", "lockstep_shm"}});
  ASSERT_EQ(offer["ok"], true) << offer;
  ASSERT_TRUE(c.take_stream(offer["result"]));
  c.send({{"op", "lockstep_join"}, {"period_s", 0.02}, {"id", "join"}});
  ASSERT_EQ(c.sleep_until_woken(), (Lines{"woken 1", "join ok", "tick 0"}));
}

Json done(int64_t tick, const std::string& id, bool quiet = true) {
  return {{"op", "done"}, {"tick", tick}, {"id", id}, {"quiet", quiet}};
}

// A lockstep client that sends its tick's requests and its quiet done in one burst is woken once
// per tick, by the tick, which finds the burst's replies before it in the ring, in order.
TEST(SharedMemoryStream, AQuietDoneWakesTheClientOncePerTickWithItsRepliesBeforeTheTick) {
  SimServer server;
  RawShmClient a(server.api_port());
  ASSERT_NO_FATAL_FAILURE(join_on_ring(a));
  ApiClient api(server.api_port());
  ASSERT_EQ(api.request({{"op", "resume"}}).value("ok", false), true);
  for (int64_t tick = 0; tick < 5; ++tick) {
    a.send_burst({{{"op", "status"}, {"id", "1"}},
                  {{"op", "status"}, {"id", "2"}},
                  {{"op", "status"}, {"id", "3"}},
                  done(tick, "done")});
    EXPECT_EQ(a.sleep_until_woken(), (Lines{"woken 1", "1 ok", "2 ok", "3 ok", "done ok",
                                            "tick " + std::to_string(tick + 1)}));
  }
}

// What may leave a quiet client waiting for something other than its tick wakes it: a request
// after its done (its reply may be awaited), a done that is refused, a done that is not quiet
// (SimConnection's, which waits for the reply), the clock idling paused. Client b, on TCP, holds
// the clock at each tick, so no tick can be what wakes a.
TEST(SharedMemoryStream, ARequestAfterTheDoneARefusedDoneAndAPauseWakeAQuietClient) {
  SimServer server;
  RawShmClient a(server.api_port());
  ASSERT_NO_FATAL_FAILURE(join_on_ring(a));
  ApiClient b(server.api_port());
  ASSERT_EQ(b.request({{"op", "lockstep_join"}, {"period_s", 0.02}}).value("ok", false), true);
  ApiClient api(server.api_port());
  ASSERT_EQ(api.request({{"op", "resume"}}).value("ok", false), true);
  auto b_done = [&b] { ASSERT_EQ(b.request({{"op", "done"}}).value("ok", false), true); };

  // a done refused before the op runs (quiet must be true or false): its error wakes
  a.send_burst({{{"op", "done"}, {"tick", 0}, {"id", "typed"}, {"quiet", 1}}});
  EXPECT_EQ(a.sleep_until_woken(), (Lines{"woken 1", "typed bad_field"}));
  // a request after the done: answered and woken for, with the done's reply before it
  a.send_burst({done(0, "done")});
  a.send({{"op", "status"}, {"id", "after"}});
  EXPECT_EQ(a.sleep_until_woken(), (Lines{"woken 1", "done ok", "after ok"}));
  // a done refused (the tick has its done): its error wakes
  a.send_burst({done(0, "again")});
  EXPECT_EQ(a.sleep_until_woken(), (Lines{"woken 1", "again bad_state"}));
  // b's done: the next tick, for both
  b_done();
  EXPECT_EQ(a.sleep_until_woken(), (Lines{"woken 1", "tick 1"}));

  // a done that does not ask for quiet is woken for at once, as before
  a.send_burst({done(1, "loud", false)});
  EXPECT_EQ(a.sleep_until_woken(), (Lines{"woken 1", "loud ok"}));
  b_done();
  EXPECT_EQ(a.sleep_until_woken(), (Lines{"woken 1", "tick 2"}));

  // paused while a is quiet: once b's done leaves the clock idle, a is woken with its reply (no
  // tick comes until a resume), and the resume's tick wakes it again
  ASSERT_EQ(api.request({{"op", "pause"}}).value("ok", false), true);
  a.send_burst({done(2, "paused")});
  b_done();
  EXPECT_EQ(a.sleep_until_woken(), (Lines{"woken 1", "paused ok"}));
  ASSERT_EQ(api.request({{"op", "resume"}}).value("ok", false), true);
  EXPECT_EQ(a.sleep_until_woken(), (Lines{"woken 1", "tick 3"}));
}

// client_cpp's lockstep loop asks for quiet in its done on the ring: it is woken by its ticks only
// (without quiet, the pass that serves each done wakes it too: about two wake-ups a tick).
TEST(SharedMemoryStream, TheLockstepLoopIsWokenOnlyByItsTicks) {
  SimServer server;
  auto l = EventLoop::create(LoopConfig::lockstep("127.0.0.1", server.api_port(), 0.02));
  ASSERT_TRUE(l) << l.message();
  ASSERT_TRUE(LoopServices(**l).sim_channel()->on_ring());
  ApiClient api(server.api_port());
  ASSERT_EQ(api.request({{"op", "resume"}}).value("ok", false), true);
  const uint64_t before = server.shm_wakeups();
  ASSERT_TRUE((*l)->run_for(1.0));
  constexpr uint64_t kTicks = 50;  // 1 s of 20 ms ticks; one more may be written as it returns
  EXPECT_LE(server.shm_wakeups() - before, kTicks + 2);
}

}  // namespace
}  // namespace uavsim::client::testing
