// SimConnection (the sim API client) against the real API server in-process over loopback (replies,
// server errors, stepping, the lockstep tick/done exchange, queued events), and against a scripted
// peer on a socketpair for what a well-behaved server never sends: frames with their binary
// payload, malformed or oversized messages, stray replies, a closed connection, silence.
#include "uavsim/client/sim_connection.hpp"

#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>
#include <thread>

#include "sim_harness.hpp"

namespace uavsim::client::testing {
namespace {

constexpr double kTimeTol_s = 1e-6;
constexpr int kPollMs = 100;
constexpr int kMaxPolls = 100;  // 10 s of wall time for a message that should come at once

std::unique_ptr<SimConnection> connect_to(const SimServer& server) {
  auto c = SimConnection::connect("127.0.0.1", static_cast<uint16_t>(server.api_port()), 10.0);
  EXPECT_TRUE(c) << c.message();
  return c ? std::move(*c) : nullptr;
}

TEST(SimConnection, ConnectReadsTheHello) {
  SimServer server;
  auto api = connect_to(server);
  ASSERT_NE(api, nullptr);
  EXPECT_EQ(api->hello().value("hello", ""), "uavsim");
  EXPECT_EQ(api->hello().value("protocol", 0), 1);
  EXPECT_TRUE(api->connected());
  EXPECT_GE(api->fd(), 0);
}

TEST(SimConnection, RequestReturnsTheResultAndServerErrorsAsFailures) {
  SimServer server;  // started paused
  auto api = connect_to(server);
  ASSERT_NE(api, nullptr);
  const auto s = api->status();
  ASSERT_TRUE(s) << s.message();
  EXPECT_TRUE(s->value("paused", false));
  EXPECT_EQ(s->value("protocol", 0), 1);

  const auto unknown = api->request({{"op", "no_such_op"}});
  ASSERT_FALSE(unknown);
  EXPECT_EQ(unknown.code(), Error::kUnsupported);
  EXPECT_NE(unknown.message().find("unknown_op"), std::string::npos) << unknown.message();

  const auto bad = api->request({{"op", "step"}, {"steps", "x"}});
  ASSERT_FALSE(bad);
  EXPECT_EQ(bad.code(), Error::kInvalidArgument);
  EXPECT_NE(bad.message().find("bad_field"), std::string::npos) << bad.message();

  EXPECT_EQ(api->request(nlohmann::json::array()).code(), Error::kInvalidArgument);
  // the connection carries on after errors
  EXPECT_TRUE(api->status());
}

TEST(SimConnection, StepForAdvancesTheClockBySimSeconds) {
  SimServer server;
  auto api = connect_to(server);
  ASSERT_NE(api, nullptr);
  const auto r = api->step_for(0.5, 30.0);
  ASSERT_TRUE(r) << r.message();
  EXPECT_NEAR(r->value("time_s", -1.0), 0.5, kTimeTol_s);
  const auto s = api->status();
  ASSERT_TRUE(s);
  EXPECT_NEAR(s->value("time_s", -1.0), 0.5, kTimeTol_s);
}

TEST(SimConnection, LockstepTicksGoToTheirHandlerAndDoneAdvancesTheClock) {
  SimServer server;
  auto api = connect_to(server);
  ASSERT_NE(api, nullptr);
  std::vector<std::pair<int64_t, double>> ticks;
  api->on_message("tick", [&](const SimMessage& m) {
    ticks.emplace_back(m.json.value("tick", int64_t{-1}), m.json.value("time", -1.0));
  });
  ASSERT_TRUE(api->lockstep_join(0.1, 30.0));
  ASSERT_TRUE(api->resume());
  // three ticks, 0.1 s of sim time apart: each comes only after the previous one's done
  for (int k = 0; k < 3; ++k) {
    for (int i = 0; i < kMaxPolls && static_cast<int>(ticks.size()) <= k; ++i) {
      ASSERT_TRUE(api->poll(kPollMs));
    }
    ASSERT_EQ(static_cast<int>(ticks.size()), k + 1);
    if (k > 0) {
      EXPECT_NEAR(ticks[k].second - ticks[k - 1].second, 0.1, kTimeTol_s);
    }
    const auto d = api->done(ticks[k].first);
    ASSERT_TRUE(d) << d.message();
  }
  for (const SimMessage& m : api->take_messages()) EXPECT_NE(m.kind(), "tick");
  EXPECT_TRUE(api->lockstep_leave());
}

TEST(SimConnection, RequestAllRunsTheRequestsAtTheTickAndReturnsEachResultInOrder) {
  SimServer server;
  auto api = connect_to(server);
  ASSERT_NE(api, nullptr);
  std::vector<double> tick_times;
  std::vector<int64_t> ticks;
  api->on_message("tick", [&](const SimMessage& m) {
    ticks.push_back(m.json.value("tick", int64_t{-1}));
    tick_times.push_back(m.json.value("time", -1.0));
  });
  ASSERT_TRUE(api->lockstep_join(0.1, 30.0));
  ASSERT_TRUE(api->resume());
  for (int i = 0; i < kMaxPolls && ticks.size() < 2; ++i) {
    ASSERT_TRUE(api->poll(kPollMs));
    if (ticks.size() == 1) {
      // between the first tick and its done: every request runs at that tick
      const auto r = api->request_all(
          {{{"op", "status"}}, {{"op", "no_such_op"}}, {{"op", "vehicles"}}, {{"op", "status"}}});
      ASSERT_EQ(r.size(), 4u);
      ASSERT_TRUE(r[0]) << r[0].message();
      EXPECT_NEAR(r[0]->value("time_s", -1.0), tick_times[0], kTimeTol_s);
      ASSERT_FALSE(r[1]);
      EXPECT_EQ(r[1].code(), Error::kUnsupported);
      EXPECT_NE(r[1].message().find("no_such_op"), std::string::npos) << r[1].message();
      ASSERT_TRUE(r[2]) << r[2].message();
      EXPECT_TRUE(r[2]->contains("vehicles"));
      ASSERT_TRUE(r[3]) << r[3].message();
      EXPECT_NEAR(r[3]->value("time_s", -1.0), tick_times[0], kTimeTol_s);
      ASSERT_TRUE(api->done(ticks[0]));
    }
  }
  ASSERT_EQ(ticks.size(), 2u);
  EXPECT_NEAR(tick_times[1] - tick_times[0], 0.1, kTimeTol_s);
  // a malformed request in the list: every result says so
  const auto bad = api->request_all({{{"op", "status"}}, nlohmann::json::array()});
  ASSERT_EQ(bad.size(), 2u);
  EXPECT_EQ(bad[0].code(), Error::kInvalidArgument);
  EXPECT_EQ(bad[1].code(), Error::kInvalidArgument);
  EXPECT_TRUE(api->request_all({}).empty());
  EXPECT_TRUE(api->lockstep_leave());
}

TEST(SimConnection, StreamedEventsAreQueuedWhileWaitingForAReply) {
  SimServer server;
  auto api = connect_to(server);
  ASSERT_NE(api, nullptr);
  ASSERT_TRUE(api->subscribe_events());
  ASSERT_TRUE(api->reset(7));
  bool reset_seen = false;
  for (int i = 0; i < kMaxPolls && !reset_seen; ++i) {
    for (const SimMessage& m : api->take_messages()) {
      if (m.kind() == "reset") {
        reset_seen = true;
        EXPECT_EQ(m.json.value("seed", 0), 7);
      }
    }
    if (!reset_seen) {
      ASSERT_TRUE(api->poll(kPollMs));
    }
  }
  EXPECT_TRUE(reset_seen);
}

TEST(SimConnection, NothingListeningIsConnectionRefused) {
  // a port that was just free
  const int probe = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ASSERT_EQ(::bind(probe, reinterpret_cast<sockaddr*>(&a), sizeof(a)), 0);
  socklen_t len = sizeof(a);
  ASSERT_EQ(::getsockname(probe, reinterpret_cast<sockaddr*>(&a), &len), 0);
  ::close(probe);
  const auto c = SimConnection::connect("127.0.0.1", ntohs(a.sin_port), 2.0);
  ASSERT_FALSE(c);
  EXPECT_EQ(c.code(), Error::kConnectionRefused);
}

// A scripted peer: the test writes what a server would (or would never) send.
class ScriptedPeer : public ::testing::Test {
 protected:
  static constexpr const char* kHello = "{\"hello\":\"uavsim\",\"protocol\":1,\"ops\":[]}\n";
  void SetUp() override {
    int fds[2];
    ASSERT_EQ(::socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, fds), 0);
    client_fd_ = fds[0];
    peer_fd_ = fds[1];
  }
  void TearDown() override {
    if (peer_fd_ >= 0) ::close(peer_fd_);
    if (client_fd_ >= 0) ::close(client_fd_);
    peer_fd_ = client_fd_ = -1;
  }
  void write_peer(const std::string& bytes) {
    ASSERT_EQ(::send(peer_fd_, bytes.data(), bytes.size(), MSG_NOSIGNAL),
              static_cast<ssize_t>(bytes.size()));
  }
  // the connection, after the hello
  std::unique_ptr<SimConnection> adopt() {
    write_peer(kHello);
    auto c = SimConnection::adopt(client_fd_, 5.0);
    client_fd_ = -1;  // the connection owns it now, or closed it
    EXPECT_TRUE(c) << c.message();
    return c ? std::move(*c) : nullptr;
  }
  int client_fd_ = -1;
  int peer_fd_ = -1;
};

TEST_F(ScriptedPeer, FramePayloadIsKeptWithItsHeaderAndTheNextMessageFollowsIt) {
  auto api = adopt();
  ASSERT_NE(api, nullptr);
  // the payload holds a newline and bytes that look like JSON: it is not read as lines
  const std::string payload = std::string("ab\n{\"x\":1}\n", 11) + std::string(1, '\0') + "z";
  write_peer("{\"event\":\"frame\",\"camera\":\"c\",\"bytes\":" + std::to_string(payload.size()) +
             "}\n" + payload + "{\"event\":\"sim_event\",\"type\":\"takeoff\"}\n");
  ASSERT_TRUE(api->poll(1000));
  const auto msgs = api->take_messages();
  ASSERT_EQ(msgs.size(), 2u);
  EXPECT_EQ(msgs[0].kind(), "frame");
  EXPECT_EQ(msgs[0].payload, payload);
  EXPECT_EQ(msgs[1].kind(), "sim_event");
  EXPECT_TRUE(msgs[1].payload.empty());
}

TEST_F(ScriptedPeer, FrameSplitAcrossReadsIsReassembled) {
  auto api = adopt();
  ASSERT_NE(api, nullptr);
  write_peer("{\"event\":\"frame\",\"bytes\":6}\nabc");
  ASSERT_TRUE(api->poll(1000));
  EXPECT_TRUE(api->take_messages().empty());
  write_peer("def");
  ASSERT_TRUE(api->poll(1000));
  const auto msgs = api->take_messages();
  ASSERT_EQ(msgs.size(), 1u);
  EXPECT_EQ(msgs[0].payload, "abcdef");
}

TEST_F(ScriptedPeer, FrameWithAnUnusableByteCountBreaksTheConnection) {
  for (const char* bytes : {"-1", "\"12\"", "1.5", "1000000000000"}) {
    TearDown();
    SetUp();
    auto api = adopt();
    ASSERT_NE(api, nullptr);
    write_peer(std::string("{\"event\":\"frame\",\"bytes\":") + bytes + "}\n");
    const auto r = api->poll(1000);
    ASSERT_FALSE(r) << bytes;
    EXPECT_EQ(r.code(), Error::kProtocol) << bytes;
    EXPECT_FALSE(api->connected());
    EXPECT_EQ(api->status().code(), Error::kProtocol);
  }
}

TEST_F(ScriptedPeer, MalformedLineIsAProtocolFailure) {
  auto api = adopt();
  ASSERT_NE(api, nullptr);
  write_peer("this is not json\n");
  const auto r = api->poll(1000);
  ASSERT_FALSE(r);
  EXPECT_EQ(r.code(), Error::kProtocol);
  EXPECT_FALSE(api->connected());
  EXPECT_EQ(api->fd(), -1);
}

TEST_F(ScriptedPeer, OversizedLineIsAProtocolFailureNotAnAllocationOfIt) {
  auto api = adopt();
  ASSERT_NE(api, nullptr);
  // more than kMaxLineBytes with no newline, written while the client reads
  std::thread writer([fd = peer_fd_] {
    const std::string chunk(1 << 16, 'x');
    for (std::size_t sent = 0; sent <= SimConnection::kMaxLineBytes + chunk.size();) {
      const ssize_t n = ::send(fd, chunk.data(), chunk.size(), MSG_NOSIGNAL);
      if (n <= 0) break;
      sent += static_cast<std::size_t>(n);
    }
  });
  Result<void> r = ok();
  for (int i = 0; i < 1000 && r; ++i) r = api->poll(kPollMs);
  writer.join();
  ASSERT_FALSE(r);
  EXPECT_EQ(r.code(), Error::kProtocol);
}

TEST_F(ScriptedPeer, RepliesOfOtherIdsAreSkippedAndTheErrorIsMapped) {
  auto api = adopt();
  ASSERT_NE(api, nullptr);
  // the first request (id 1) is answered late: it times out, then its reply is skipped
  EXPECT_EQ(api->request({{"op", "status"}}, 0.05).code(), Error::kTimeout);
  write_peer(
      "{\"id\":1,\"ok\":true,\"result\":{\"stale\":true}}\n"
      "{\"event\":\"tick\",\"tick\":3,\"time\":0.15}\n"
      "{\"id\":2,\"ok\":false,\"error\":{\"code\":\"not_available\",\"message\":\"no truck\"}}\n");
  const auto r = api->truck();
  ASSERT_FALSE(r);
  EXPECT_EQ(r.code(), Error::kUnsupported);
  EXPECT_NE(r.message().find("not_available: no truck"), std::string::npos) << r.message();
  const auto msgs = api->take_messages();
  ASSERT_EQ(msgs.size(), 1u);
  EXPECT_EQ(msgs[0].kind(), "tick");
  EXPECT_TRUE(api->connected());
}

TEST_F(ScriptedPeer, RequestAllSendsEveryRequestBeforeAnyReplyComes) {
  auto api = adopt();
  ASSERT_NE(api, nullptr);
  // the peer answers only once it has read both requests: a client that waited for the first
  // reply before sending the second would time out
  std::string got;
  std::thread peer([&] {
    char buf[4096];
    while (std::count(got.begin(), got.end(), '\n') < 2) {
      pollfd p{peer_fd_, POLLIN, 0};
      if (::poll(&p, 1, 10000) <= 0) return;
      const ssize_t n = ::recv(peer_fd_, buf, sizeof(buf), 0);
      if (n <= 0) return;
      got.append(buf, static_cast<size_t>(n));
    }
    write_peer(
        "{\"id\":1,\"ok\":true,\"result\":{\"time_s\":1.5}}\n"
        "{\"id\":2,\"ok\":false,\"error\":{\"code\":\"not_available\",\"message\":\"no "
        "truck\"}}\n");
  });
  const auto r = api->request_all({{{"op", "status"}}, {{"op", "truck"}}}, 20.0);
  peer.join();
  ASSERT_EQ(r.size(), 2u);
  ASSERT_TRUE(r[0]) << r[0].message();
  EXPECT_EQ(r[0]->value("time_s", 0.0), 1.5);
  ASSERT_FALSE(r[1]);
  EXPECT_EQ(r[1].code(), Error::kUnsupported);
  EXPECT_NE(got.find("\"op\":\"status\""), std::string::npos) << got;
  EXPECT_LT(got.find("\"op\":\"status\""), got.find("\"op\":\"truck\"")) << got;
  // a malformed request: nothing is sent
  const auto bad = api->request_all({{{"op", "status"}}, {{"no_op", 1}}});
  EXPECT_EQ(bad[0].code(), Error::kInvalidArgument);
  char c;
  EXPECT_EQ(::recv(peer_fd_, &c, 1, MSG_DONTWAIT), -1);
}

TEST_F(ScriptedPeer, ClosedConnectionFailsTheWaitingRequest) {
  auto api = adopt();
  ASSERT_NE(api, nullptr);
  ::shutdown(peer_fd_, SHUT_WR);
  const auto r = api->status();
  ASSERT_FALSE(r);
  EXPECT_EQ(r.code(), Error::kConnectionLost);
  EXPECT_FALSE(api->connected());
  EXPECT_EQ(api->pause().code(), Error::kConnectionLost);
}

TEST_F(ScriptedPeer, PeerThatIsNotAUavsimServerIsRefused) {
  write_peer("{\"hello\":\"other\"}\n");
  const auto c = SimConnection::adopt(client_fd_, 5.0);
  client_fd_ = -1;
  ASSERT_FALSE(c);
  EXPECT_EQ(c.code(), Error::kProtocol);
}

TEST_F(ScriptedPeer, SilentPeerTimesOut) {
  const auto c = SimConnection::adopt(client_fd_, 0.1);
  client_fd_ = -1;
  ASSERT_FALSE(c);
  EXPECT_EQ(c.code(), Error::kTimeout);
}

}  // namespace
}  // namespace uavsim::client::testing
