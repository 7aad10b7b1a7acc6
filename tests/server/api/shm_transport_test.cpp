// When the shared-memory stream wakes its reader (api/shm_transport.hpp; docs/protocol.md,
// "Shared-memory stream"): once per gate pass, and for a lockstep client whose done was accepted
// not before its next tick, which brings what was written meanwhile. Driven on the test thread as
// the gate drives it (hold, writes, release), with the wake-ups counted as the bytes in the FIFO.
#include "api/shm_transport.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/mman.h>
#include <sys/socket.h>
#include <unistd.h>

#include <future>
#include <string>
#include <thread>
#include <vector>

#include "../../support/loopback_tcp.hpp"
#include "api/line_server.hpp"
#include "uavsim/common/shm_ring.hpp"

namespace uavsim::server::api {
namespace {

namespace shm = common::shm;

// One connection of a LineServer with its output on a ring; the test is the reader.
class RingFixture : public ::testing::Test {
 protected:
  void SetUp() override {
    std::promise<uint64_t> connected;
    LineServer::Callbacks cb;
    cb.on_connect = [&connected](uint64_t conn) { connected.set_value(conn); };
    server_ = std::make_unique<LineServer>("127.0.0.1", 0, LineServer::Limits{}, cb);
    server_->start();
    socket_ = socket(AF_INET, SOCK_STREAM, 0);
    ASSERT_TRUE(uavsim::testing::connect_loopback_tcp(socket_, server_->port()));
    conn_ = connected.get_future().get();
    transport_ = std::make_unique<ShmTransport>(*server_);
    std::string why;
    const auto offer = transport_->offer(conn_, shm::kMinCapacity, 0, &why);
    ASSERT_TRUE(offer) << why;
    const std::string token = (*offer)["token"];
    size_ = shm::region_bytes(shm::kMinCapacity);
    const int fd = shm_open(shm::object_name(token).c_str(), O_RDWR, 0);
    ASSERT_GE(fd, 0);
    region_ = mmap(nullptr, size_, PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0);
    close(fd);
    ASSERT_NE(region_, MAP_FAILED);
    fifo_ = open(shm::fifo_path(token).c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
    ASSERT_GE(fifo_, 0);
    auto reader = shm::RingReader::attach(region_, size_, &why);
    ASSERT_TRUE(reader) << why;
    reader_.emplace(*reader);
    transport_->activate(conn_);
    ASSERT_TRUE(transport_->attached(conn_));
    reader_->arm();  // asleep, waiting for its first wake-up
  }
  void TearDown() override {
    transport_.reset();
    server_.reset();
    if (region_ != nullptr && region_ != MAP_FAILED) munmap(region_, size_);
    if (fifo_ >= 0) close(fifo_);
    if (socket_ >= 0) close(socket_);
  }

  void send(const std::string& line) { ASSERT_TRUE(server_->send(conn_, line + "\n")); }
  void tick(int64_t n) { ASSERT_TRUE(transport_->send_tick(conn_, n, 0.05 * n)); }
  // the wake-up bytes waiting in the FIFO, taken
  int wakes() {
    int n = 0;
    char buf[64];
    for (ssize_t got; (got = read(fifo_, buf, sizeof(buf))) > 0;) n += static_cast<int>(got);
    return n;
  }
  // as a woken client: the flag cleared, then every record there is ("tick N" for a tick record)
  std::vector<std::string> read_all() {
    reader_->arm();
    std::vector<std::string> out;
    shm::RingReader::Record rec;
    std::string why;
    while (reader_->next(&rec, &why) == shm::RingReader::Status::kRecord) {
      if (rec.type == shm::RecordType::kTick) {
        const auto t = shm::decode_tick(rec.payload, &why);
        out.push_back(t ? "tick " + std::to_string(t->tick) : "bad tick: " + why);
      } else {
        out.emplace_back(rec.payload.begin(), rec.payload.end() - 1);  // without the newline
      }
    }
    return out;
  }

  // kWrites records written on another thread while this one runs as many gate passes
  static constexpr int kWrites = 1000;
  void write_from_another_thread_during_passes() {
    std::thread writer([&] {
      for (int i = 0; i < kWrites; ++i) send("record");
    });
    for (int pass = 0; pass < kWrites; ++pass) {
      transport_->hold_wakeups();
      transport_->release_wakeups();
    }
    writer.join();
  }

  std::unique_ptr<LineServer> server_;
  std::unique_ptr<ShmTransport> transport_;
  uint64_t conn_ = 0;
  int socket_ = -1;
  void* region_ = nullptr;
  std::size_t size_ = 0;
  int fifo_ = -1;
  std::optional<shm::RingReader> reader_;
};

using Lines = std::vector<std::string>;

TEST_F(RingFixture, AGatePassWakesTheReaderOnceForAllItWrote) {
  transport_->hold_wakeups();
  send("r1");
  send("r2");
  send("r3");
  EXPECT_EQ(wakes(), 0);
  transport_->release_wakeups();
  EXPECT_EQ(wakes(), 1);
  EXPECT_EQ(read_all(), (Lines{"r1", "r2", "r3"}));
  // outside a pass each write wakes a reader that has armed again
  send("r4");
  EXPECT_EQ(wakes(), 1);
}

// The lockstep client's burst: replies to its requests, then its done, in one pass; one wake-up,
// its next tick's, brings them all in order.
TEST_F(RingFixture, ADoneAcceptedPutsThePassWakeupOffToTheNextTick) {
  for (int64_t t = 1; t <= 3; ++t) {
    transport_->hold_wakeups();
    send("radio " + std::to_string(t));
    send("radio' " + std::to_string(t));
    transport_->quiet_until_tick(conn_);
    send("done " + std::to_string(t));
    transport_->release_wakeups();
    EXPECT_EQ(wakes(), 0) << t;
    // events written before the tick, from the loop or another thread, outside a pass
    send("event " + std::to_string(t));
    std::thread([&] { send("event' " + std::to_string(t)); }).join();
    EXPECT_EQ(wakes(), 0) << t;
    transport_->hold_wakeups();
    tick(t);
    EXPECT_EQ(wakes(), 0) << t;  // held to the end of the pass
    transport_->release_wakeups();
    EXPECT_EQ(wakes(), 1) << t;
    EXPECT_EQ(read_all(), (Lines{"radio " + std::to_string(t), "radio' " + std::to_string(t),
                                 "done " + std::to_string(t), "event " + std::to_string(t),
                                 "event' " + std::to_string(t), "tick " + std::to_string(t)}));
  }
}

// A camera frame (written by the render thread, work_ahead) wakes a quiet reader as it comes, with
// the replies before it, so that its vision runs while the simulation steps on; what comes after
// it without work_ahead waits for the tick again.
TEST_F(RingFixture, ACameraFrameWakesAQuietReaderTheRepliesAndEventsStillWait) {
  auto frame = [&](const std::string& name) {
    std::thread([&] {
      ASSERT_TRUE(server_->send(conn_, name + "\n", /*work_ahead=*/true));
    }).join();
  };
  transport_->hold_wakeups();
  send("radio 1");
  transport_->quiet_until_tick(conn_);
  send("done 1");
  transport_->release_wakeups();
  EXPECT_EQ(wakes(), 0);
  frame("frame 1");
  EXPECT_EQ(wakes(), 1);
  EXPECT_EQ(read_all(), (Lines{"radio 1", "done 1", "frame 1"}));
  send("event 1");  // still quiet
  EXPECT_EQ(wakes(), 0);
  // a frame during a gate pass wakes at its end, quiet or not
  transport_->hold_wakeups();
  frame("frame 2");
  EXPECT_EQ(wakes(), 0);
  transport_->release_wakeups();
  EXPECT_EQ(wakes(), 1);
  EXPECT_EQ(read_all(), (Lines{"event 1", "frame 2"}));
  transport_->hold_wakeups();
  tick(1);
  transport_->release_wakeups();
  EXPECT_EQ(wakes(), 1);
  EXPECT_EQ(read_all(), (Lines{"tick 1"}));
}

// A request after the done: its reply may be awaited, so it wakes, with what came before it.
TEST_F(RingFixture, EndingTheQuietWakesForWhatWasWrittenMeanwhile) {
  transport_->hold_wakeups();
  transport_->quiet_until_tick(conn_);
  send("done");
  transport_->release_wakeups();
  EXPECT_EQ(wakes(), 0);
  transport_->hold_wakeups();
  transport_->end_quiet(conn_);
  send("status");
  EXPECT_EQ(wakes(), 0);
  transport_->release_wakeups();
  EXPECT_EQ(wakes(), 1);
  EXPECT_EQ(read_all(), (Lines{"done", "status"}));
  // no longer quiet: the next write wakes as usual
  send("event");
  EXPECT_EQ(wakes(), 1);
  // outside a pass the end of the quiet wakes at once
  transport_->quiet_until_tick(conn_);
  EXPECT_EQ(read_all(), (Lines{"event"}));
  send("late");
  EXPECT_EQ(wakes(), 0);
  transport_->end_quiet(conn_);
  EXPECT_EQ(wakes(), 1);
  EXPECT_EQ(read_all(), (Lines{"late"}));
  // a quiet with nothing written ends without a wake-up
  transport_->quiet_until_tick(conn_);
  transport_->end_quiet(conn_);
  EXPECT_EQ(wakes(), 0);
}

// A reset or a stopping server (end_quiet_all), and the connection's end (on_disconnect).
TEST_F(RingFixture, EveryOtherEndOfTheQuietWakes) {
  transport_->quiet_until_tick(conn_);
  send("done");
  transport_->end_quiet_all();
  EXPECT_EQ(wakes(), 1);
  EXPECT_EQ(read_all(), (Lines{"done"}));
  transport_->quiet_until_tick(conn_);
  send("done");
  EXPECT_EQ(wakes(), 0);
  transport_->on_disconnect(conn_);
  EXPECT_EQ(wakes(), 1);
  EXPECT_EQ(read_all(), (Lines{"done"}));
}

// A reader that has not armed again since its last wake-up has one coming (or is awake): the tick
// after a quiet wakes nobody twice, and the flag it leaves set still lets the next armed sleep be
// woken.
TEST_F(RingFixture, AReaderStillAwakeIsNotWokenAgainAndLosesNoLaterWakeup) {
  send("r1");
  EXPECT_EQ(wakes(), 1);  // not armed again: awake
  transport_->quiet_until_tick(conn_);
  send("done");
  tick(1);
  EXPECT_EQ(wakes(), 0);
  EXPECT_EQ(read_all(), (Lines{"r1", "done", "tick 1"}));
  transport_->quiet_until_tick(conn_);
  send("done");
  tick(2);
  EXPECT_EQ(wakes(), 1);
  EXPECT_EQ(read_all(), (Lines{"done", "tick 2"}));
}

// Writers on another thread race the gate's passes and the quiet: while quiet nothing wakes, and
// the quiet's end wakes once.
TEST_F(RingFixture, WritesFromAnotherThreadWhileQuietWakeOnceAtTheEnd) {
  transport_->quiet_until_tick(conn_);
  write_from_another_thread_during_passes();
  EXPECT_EQ(wakes(), 0);
  transport_->end_quiet(conn_);
  EXPECT_EQ(wakes(), 1);
  EXPECT_EQ(read_all().size(), static_cast<size_t>(kWrites));
}

// Without quiet, a write from another thread during a pass is woken for at its end: none is lost
// whichever side of the release it falls.
TEST_F(RingFixture, WritesFromAnotherThreadDuringPassesAreAllWokenFor) {
  write_from_another_thread_during_passes();
  EXPECT_EQ(wakes(), 1);  // the reader never armed again: one byte in flight at most
  EXPECT_EQ(read_all().size(), static_cast<size_t>(kWrites));
  send("last");
  EXPECT_EQ(wakes(), 1);
}

}  // namespace
}  // namespace uavsim::server::api
