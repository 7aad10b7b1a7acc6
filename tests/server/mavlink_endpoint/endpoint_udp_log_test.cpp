// The endpoint's UDP links (ArduPilot's udpclient and udpin) and its telemetry logs: a ground station on a
// UDP port gets the vehicle's stream and is answered on the same socket; a .tlog holds every frame a
// client received and sent, in order, with monotonic sim-time stamps.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>

#include "../../support/loopback_udp.hpp"
#include "mavlink/tlog.hpp"
#include "mavlink_endpoint/test_gcs.hpp"

namespace uavsim::server::mavlink::testing {
namespace {

// a ground station on a UDP socket bound to an ephemeral loopback port
class UdpGcs {
 public:
  UdpGcs() { fd_ = uavsim::testing::bind_loopback_udp(&port_, SOCK_NONBLOCK); }
  ~UdpGcs() { close(fd_); }
  int port() const { return port_; }
  // reads every waiting datagram; remembers the sender (the vehicle's port) and the frames
  void poll_once() {
    std::uint8_t buf[65536];
    for (;;) {
      sockaddr_in from{};
      socklen_t len = sizeof(from);
      const ssize_t n = recvfrom(fd_, buf, sizeof(buf), 0, reinterpret_cast<sockaddr*>(&from), &len);
      if (n <= 0) return;
      ++datagrams_;
      vehicle_port_ = ntohs(from.sin_port);
      parser_.feed({buf, static_cast<std::size_t>(n)}, [&](const Frame& f) { msgids_.push_back(f.msgid); });
    }
  }
  template <class Msg>
  void send_to(int port, const Msg& m) {
    FrameHeader h;
    h.sysid = 255;
    h.compid = 190;
    h.seq = seq_++;
    const EncodedFrame f = encode(h, m);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_port = htons(static_cast<std::uint16_t>(port));
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    sendto(fd_, f.bytes.data(), f.size, 0, reinterpret_cast<sockaddr*>(&a), sizeof(a));
  }
  std::size_t count(std::uint32_t msgid) const { return std::count(msgids_.begin(), msgids_.end(), msgid); }
  std::size_t datagrams() const { return datagrams_; }
  std::size_t frames() const { return msgids_.size(); }
  int vehicle_port() const { return vehicle_port_; }

 private:
  int fd_ = -1;
  std::uint16_t port_ = 0;
  int vehicle_port_ = 0;
  std::uint8_t seq_ = 0;
  std::size_t datagrams_ = 0;
  Parser parser_;
  std::vector<std::uint32_t> msgids_;
};

class EndpointUdpTest : public EndpointTest {
 protected:
  void SetUp() override {}
  void start_with(EndpointConfig c) {
    sim_ = sim::testing::make_sim("empty.xml");
    c.base_port = 0;
    server_ = std::make_unique<MavlinkServer>(*sim_, c);
    server_->schedule(sim_->schedule());
  }
  // steps control periods until pred() holds for what gcs received (at most max_sim_s of sim time)
  bool step_until_udp(UdpGcs& gcs, const std::function<bool()>& pred, double max_sim_s) {
    const double end = sim_->time_s() + max_sim_s;
    while (sim_->time_s() < end) {
      for (int k = 0; k < sim_->control_decimation(); ++k) sim_->step();
      gcs.poll_once();
      if (pred()) return true;
    }
    return wait_for([&] {
      gcs.poll_once();
      return pred();
    }, 2.0);
  }
};

TEST_F(EndpointUdpTest, StreamsToAGroundStationAndAnswersItOnTheSameSocket) {
  UdpGcs gcs;
  EndpointConfig c;
  c.udp = {{UdpEndpoint{false, "127.0.0.1", gcs.port()}}};
  start_with(c);
  // the stream starts unasked: heartbeats, one frame per datagram
  ASSERT_TRUE(step_until_udp(gcs, [&] { return gcs.count(msg::Heartbeat::kId) >= 2; }, 3.0));
  EXPECT_EQ(gcs.datagrams(), gcs.frames());
  EXPECT_EQ(gcs.vehicle_port(), server_->udp_port(0, 0));
  // a command sent back to the port the stream comes from is acknowledged
  msg::CommandLong cmd;
  cmd.target_system = 1;
  cmd.target_component = 1;
  cmd.command = cmd_id(MavCmd::RequestMessage);  // REQUEST_MESSAGE AUTOPILOT_VERSION
  cmd.param1 = 148;
  gcs.send_to(gcs.vehicle_port(), cmd);
  ASSERT_TRUE(wait_for([&] { return server_->stats(0).frames_received >= 1; }));
  ASSERT_TRUE(step_until_udp(gcs, [&] {
    return gcs.count(msg::CommandAck::kId) >= 1 && gcs.count(msg::AutopilotVersion::kId) >= 1;
  }, 1.0));
  EXPECT_EQ(server_->stats(0).clients_accepted, 1u);
}

TEST_F(EndpointUdpTest, UdpinAnswersTheFirstPeerThatSends) {
  EndpointConfig c;
  c.udp = {{UdpEndpoint{true, "127.0.0.1", 0}}};
  start_with(c);
  UdpGcs gcs;
  step_for(0.5);
  gcs.poll_once();
  EXPECT_EQ(gcs.frames(), 0u);  // nobody to talk to yet
  msg::Heartbeat hb;
  hb.type = 6;
  hb.autopilot = 8;
  gcs.send_to(server_->udp_port(0, 0), hb);
  ASSERT_TRUE(wait_for([&] { return server_->stats(0).clients_accepted == 1; }));
  ASSERT_TRUE(step_until_udp(gcs, [&] { return gcs.count(msg::Heartbeat::kId) >= 2; }, 3.0));
  EXPECT_EQ(gcs.vehicle_port(), server_->udp_port(0, 0));
}

TEST_F(EndpointUdpTest, TlogHoldsWhatTheClientReceivedAndSentWithMonotonicSimStamps) {
  const std::string dir = ::testing::TempDir() + "tlog_test";
  std::filesystem::create_directories(dir);
  EndpointConfig c;
  c.tlog_dir = dir;
  start_with(c);
  auto g = connect();
  // a ground station's traffic: heartbeats, a stream request, a command
  msg::Heartbeat hb;
  hb.type = 6;
  hb.autopilot = 8;
  g->send(hb);
  msg::RequestDataStream rds;
  rds.target_system = 1;
  rds.target_component = 1;
  rds.req_stream_id = 0;
  rds.req_message_rate = 10;
  rds.start_stop = 1;
  g->send(rds);
  sync_client(*g);
  step_for(2.0);
  EXPECT_EQ(command(*g, MavCmd::RequestMessage, {148}),
            0);  // REQUEST_MESSAGE AUTOPILOT_VERSION: accepted
  step_for(1.0);
  // everything the endpoint queued is written, and has arrived, before the log is closed
  ASSERT_TRUE(server_->flush_queued());
  ASSERT_TRUE(wait_for([&] {
    g->poll_once(10);
    return g->bytes_received() == server_->stats(0).bytes_sent;
  }));
  const double end_s = sim_->time_s();
  const std::uint64_t gcs_sent = g->sent_frames();
  server_.reset();  // closes (flushes) the log

  const std::vector<TlogRecord> log = read_tlog(dir + "/uav0.tlog");
  ASSERT_FALSE(log.empty());
  std::vector<Frame> from_vehicle;
  std::size_t from_gcs = 0;
  std::uint64_t last_us = 0;
  Parser parser;
  for (const TlogRecord& r : log) {
    EXPECT_GE(r.stamp_us, last_us);
    last_us = r.stamp_us;
    std::size_t parsed = 0;
    parser.feed(r.frame, [&](const Frame& f) {
      ++parsed;
      if (f.sysid == 1) {
        from_vehicle.push_back(f);
        from_vehicle.back().raw = {};
      } else {
        ++from_gcs;
      }
    });
    EXPECT_EQ(parsed, 1u) << "each record is one whole frame";
  }
  EXPECT_LE(last_us, static_cast<std::uint64_t>(end_s * 1e6) + 1);
  EXPECT_GT(last_us, static_cast<std::uint64_t>((end_s - 0.5) * 1e6));
  EXPECT_EQ(from_gcs, gcs_sent);
  // frame for frame what the client received: id, sequence number and payload
  const std::vector<Frame>& got = g->frames();
  ASSERT_EQ(from_vehicle.size(), got.size());
  for (std::size_t i = 0; i < got.size(); ++i) {
    ASSERT_EQ(from_vehicle[i].msgid, got[i].msgid) << i;
    ASSERT_EQ(from_vehicle[i].seq, got[i].seq) << i;
    ASSERT_EQ(from_vehicle[i].payload_len, got[i].payload_len) << i;
    ASSERT_TRUE(std::equal(got[i].payload.begin(), got[i].payload.begin() + got[i].payload_len,
                           from_vehicle[i].payload.begin()))
        << "frame " << i << " (msgid " << got[i].msgid << ")";
  }
}

TEST(Tlog, StampsStayMonotonicWhenTheSimClockRestarts) {
  const std::string path = ::testing::TempDir() + "restart.tlog";
  const std::uint8_t frame[] = {0xFE, 0, 0, 1, 1, 0, 0x12, 0x34};  // a v1 frame with an empty payload
  {
    TlogWriter w(path);
    w.write(2.0, frame);
    w.write(0.5, frame);  // a reset: sim time back to 0.5 s
    w.write(0.75, frame);
  }
  const auto log = read_tlog(path);
  ASSERT_EQ(log.size(), 3u);
  EXPECT_EQ(log[0].stamp_us, 2000000u);
  EXPECT_EQ(log[1].stamp_us, 2000000u);
  EXPECT_EQ(log[2].stamp_us, 2250000u);
  EXPECT_EQ(log[2].frame.size(), sizeof(frame));
}

// A server killed with SIGKILL: its tlog holds every frame but those of the last 0.1 s of sim
// before the newest, each whole (tlog.hpp's bound). 5 s of frames at 100 Hz, 16 bytes a record:
// 8000 bytes, all of which an iostream's buffer would have kept in memory and lost.
TEST(Tlog, AKilledWriterLeavesEveryFrameButTheLastTenthOfASecond) {
  const std::string path = ::testing::TempDir() + "killed.tlog";
  const std::uint8_t frame[] = {0xFE, 0, 0, 1, 1, 0, 0x12, 0x34};
  constexpr int kFrames = 500;
  constexpr double kPeriod_s = 0.01;
  const pid_t pid = fork();
  if (pid == 0) {
    TlogWriter w(path);
    for (int k = 0; k < kFrames; ++k) w.write(k * kPeriod_s, frame);
    raise(SIGKILL);  // no destructor, no flush: what a kill leaves
    _exit(0);
  }
  int status = 0;
  waitpid(pid, &status, 0);
  ASSERT_TRUE(WIFSIGNALED(status));
  const auto log = read_tlog(path);
  const double newest_s = (kFrames - 1) * kPeriod_s;
  ASSERT_FALSE(log.empty());
  EXPECT_GE(log.back().stamp_us / 1e6, newest_s - TlogWriter::kFlushSpan_s - kPeriod_s) << log.size();
  // whole frames, in order, none missing before the last one kept
  for (std::size_t i = 0; i < log.size(); ++i) {
    EXPECT_EQ(log[i].stamp_us, std::uint64_t(std::llround(i * kPeriod_s * 1e6))) << i;
    EXPECT_EQ(log[i].frame.size(), sizeof(frame)) << i;
  }
  EXPECT_EQ(std::filesystem::file_size(path), log.size() * (8 + sizeof(frame)));
}

}  // namespace
}  // namespace uavsim::server::mavlink::testing
