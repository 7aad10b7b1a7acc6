// A minimal ground station for endpoint tests: a blocking-connect, non-blocking-read TCP client
// with our codec, plus a fixture that owns a Simulation and a MavlinkServer on ephemeral ports.
// Synchronisation is by observable state only: the sim is stepped on the test thread until the
// expected frame arrives (with a sim-time bound); waiting on the I/O thread is bounded by a
// wall-clock timeout, never a fixed sleep.
#pragma once

#include <arpa/inet.h>
#include <fcntl.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <functional>
#include <memory>
#include <optional>
#include <vector>

#include "mavlink/endpoint.hpp"
#include "sim/sim_fixture.hpp"
#include "uavsim/common/mavlink/codec.hpp"
#include "uavsim/common/mavlink/generated/messages.hpp"
#include "uavsim/common/mavlink/parser.hpp"
#include "uavsim/common/mavlink/signing.hpp"

// the endpoint tests speak the common codec unqualified, as the endpoint does
namespace uavsim::server::mavlink {
using namespace ::uavsim::common::mavlink;
}  // namespace uavsim::server::mavlink

namespace uavsim::server::mavlink::testing {

// a command's number as COMMAND_LONG and MISSION_ITEM_INT carry it
constexpr std::uint16_t cmd_id(MavCmd cmd) {
  return static_cast<std::uint16_t>(to_underlying(cmd));
}
// a command ArduCopter does not serve (MAV_CMD_WAYPOINT_USER_1): answered UNSUPPORTED
constexpr MavCmd kUnsupportedCmd = MavCmd::WaypointUser1;
// whether a bitmask field (base_mode, flags, ...) has flag's bit set
template <typename Flag>
constexpr bool has_flag(std::uint64_t bits, Flag flag) {
  return (bits & to_underlying(flag)) != 0;
}

class TestGcs {
 public:
  // receive_buffer_bytes > 0 shrinks the socket's receive buffer (a client that reads slowly fills
  // up fast)
  explicit TestGcs(std::uint16_t port, Version version = Version::kV2, int receive_buffer_bytes = 0)
      : version_(version) {
    fd_ = socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    if (receive_buffer_bytes > 0) {
      setsockopt(fd_, SOL_SOCKET, SO_RCVBUF, &receive_buffer_bytes, sizeof(receive_buffer_bytes));
    }
    sockaddr_in sa{};
    sa.sin_family = AF_INET;
    sa.sin_port = htons(port);
    inet_pton(AF_INET, "127.0.0.1", &sa.sin_addr);
    connected_ = connect(fd_, reinterpret_cast<sockaddr*>(&sa), sizeof(sa)) == 0;
    fcntl(fd_, F_SETFL, fcntl(fd_, F_GETFL) | O_NONBLOCK);
    const int one = 1;
    setsockopt(fd_, IPPROTO_TCP, TCP_NODELAY, &one, sizeof(one));
  }
  ~TestGcs() { close_now(); }
  TestGcs(const TestGcs&) = delete;
  TestGcs& operator=(const TestGcs&) = delete;

  bool connected() const { return connected_; }
  void close_now() {
    if (fd_ >= 0) close(fd_);
    fd_ = -1;
  }

  template <class Msg>
  void send(const Msg& m, std::uint8_t sysid = 255, std::uint8_t compid = 190) {
    FrameHeader h;
    h.sysid = sysid;
    h.compid = compid;
    h.seq = seq_++;
    h.version = version_;
    if (signing_) {
      h.signing = *signing_;
      h.signing->timestamp_10us = timestamps_.next(signing_->timestamp_10us);
    }
    const EncodedFrame f = encode(h, m);
    ASSERT_FALSE(f.empty());
    send_raw(f.view());
    ++sent_frames_;
  }
  void send_raw(std::span<const std::uint8_t> bytes) {
    std::size_t off = 0;
    while (off < bytes.size()) {
      const ssize_t n = ::send(fd_, bytes.data() + off, bytes.size() - off, MSG_NOSIGNAL);
      if (n > 0) {
        off += static_cast<std::size_t>(n);
      } else {
        pollfd p{fd_, POLLOUT, 0};
        poll(&p, 1, 100);
      }
    }
  }
  std::uint64_t sent_frames() const { return sent_frames_; }

  // signs what send() sends from now on (timestamps from start_10us, strictly increasing); nullopt:
  // unsigned
  void sign_with(std::optional<SigningParams> signing) { signing_ = signing; }
  // checks what arrives against key from now on: frames that are unsigned or wrongly signed are
  // dropped and counted in parser_stats()
  void verify_with(const SecretKey& key) {
    ParserConfig c;
    c.signing_key = key;
    parser_.configure(c);
  }
  const ParserStats& parser_stats() const { return parser_.stats(); }

  // reads whatever has arrived, waiting at most timeout_ms for the first byte
  void poll_once(int timeout_ms) {
    pollfd p{fd_, POLLIN, 0};
    if (poll(&p, 1, timeout_ms) <= 0) return;
    std::uint8_t buf[65536];
    for (;;) {
      const ssize_t n = recv(fd_, buf, sizeof(buf), 0);
      if (n <= 0) return;
      bytes_received_ += static_cast<std::size_t>(n);
      if (first_byte_ < 0) first_byte_ = buf[0];
      parser_.feed({buf, static_cast<std::size_t>(n)}, [&](const Frame& f) {
        frames_.push_back(f);
        frames_.back().raw = {};
      });
    }
  }

  const std::vector<Frame>& frames() const { return frames_; }
  void clear() { frames_.clear(); }
  int first_byte() const { return first_byte_; }
  std::size_t bytes_received() const { return bytes_received_; }

  template <class Msg>
  std::vector<Msg> all() const {
    std::vector<Msg> out;
    for (const Frame& f : frames_) {
      if (f.msgid == Msg::kId) out.push_back(Msg::decode(f.payload.data()));
    }
    return out;
  }
  template <class Msg>
  std::optional<Msg> last() const {
    for (auto it = frames_.rbegin(); it != frames_.rend(); ++it) {
      if (it->msgid == Msg::kId) return Msg::decode(it->payload.data());
    }
    return std::nullopt;
  }
  template <class Msg>
  std::size_t count() const {
    std::size_t n = 0;
    for (const Frame& f : frames_) n += f.msgid == Msg::kId;
    return n;
  }
  const Frame* last_frame(std::uint32_t msgid) const {
    for (auto it = frames_.rbegin(); it != frames_.rend(); ++it) {
      if (it->msgid == msgid) return &*it;
    }
    return nullptr;
  }

 private:
  int fd_ = -1;
  bool connected_ = false;
  Version version_;
  std::uint8_t seq_ = 0;
  std::uint64_t sent_frames_ = 0;
  std::optional<SigningParams> signing_;
  TimestampSource timestamps_;
  Parser parser_;
  std::vector<Frame> frames_;
  int first_byte_ = -1;
  std::size_t bytes_received_ = 0;
};

class EndpointTest : public ::testing::Test {
 protected:
  // wall-clock bound for the I/O thread to write what the control steps queued (a loaded machine)
  static constexpr double kFlushTimeoutS = 10.0;

  void start(const std::string& world = "empty.xml") {
    sim_ = sim::testing::make_sim(world);
    EndpointConfig c;
    c.base_port = 0;
    server_ = std::make_unique<MavlinkServer>(*sim_, c);
    server_->schedule(sim_->schedule());
  }
  void SetUp() override { start(); }
  void TearDown() override {
    clients_.clear();
    server_.reset();
    sim_.reset();
  }

  // waits (wall clock, bounded) for a condition that the I/O thread makes true
  static bool wait_for(const std::function<bool()>& done, double timeout_s = 5.0) {
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
    while (!done()) {
      if (std::chrono::steady_clock::now() > end) return false;
      poll(nullptr, 0, 1);
    }
    return true;
  }

  // connects a client and waits until the endpoint has accepted it
  std::unique_ptr<TestGcs> connect(std::size_t vehicle = 0, Version v = Version::kV2,
                                   int rcvbuf = 0) {
    const std::size_t before = server_->stats(vehicle).clients_accepted;
    auto g = std::make_unique<TestGcs>(server_->port(vehicle), v, rcvbuf);
    EXPECT_TRUE(g->connected());
    if (vehicle == 0) clients_.push_back(g.get());
    EXPECT_TRUE(wait_for([&] { return server_->stats(vehicle).clients_accepted > before; }));
    return g;
  }

  // waits until the endpoint has parsed every frame the clients sent (so the next step handles
  // them)
  void sync(std::uint64_t frames_sent_total, std::size_t vehicle = 0) {
    ASSERT_TRUE(wait_for([&] {
      return server_->stats(vehicle).frames_received >= frames_sent_total;
    })) << "endpoint never received the frames";
  }

  // steps whole control periods until pred() holds over what g received; false after max_sim_s.
  // pred() sees every frame of the periods stepped so far: after a period that queued frames, the
  // I/O thread is waited for (wall clock, bounded) until it has written them. Otherwise the sim,
  // stepped far faster than real time, runs ahead of a slow I/O thread (a loaded machine), and
  // pred() judges old telemetry: a reply counted by a streamed copy of its message from seconds of
  // sim time before.
  bool step_until(TestGcs& g, const std::function<bool()>& pred, double max_sim_s) {
    const double end = sim_->time_s() + max_sim_s;
    std::uint64_t queued = frames_queued();
    while (sim_->time_s() < end) {
      for (int k = 0; k < sim_->control_decimation(); ++k) sim_->step();
      if (const std::uint64_t now = frames_queued(); now != queued) {
        queued = now;
        EXPECT_TRUE(server_->flush_queued(kFlushTimeoutS))
            << "the I/O thread never wrote the frames";
      }
      g.poll_once(0);
      if (pred()) return true;
    }
    // the last frames written may still be on their way into g's socket
    const auto wall_end = std::chrono::steady_clock::now() + std::chrono::seconds(2);
    while (std::chrono::steady_clock::now() < wall_end) {
      g.poll_once(10);
      if (pred()) return true;
    }
    return false;
  }

  // frames queued so far to the clients of every vehicle (telemetry and replies)
  std::uint64_t frames_queued() const {
    std::uint64_t n = 0;
    for (std::size_t v = 0; v < server_->vehicle_count(); ++v) n += server_->stats(v).frames_sent;
    return n;
  }

  // steps one control period (the loop thread handles what the endpoint has parsed) and then waits,
  // wall clock bounded, until pred() holds over what g received: a request-reply exchange that does
  // not depend on how fast the I/O thread runs and, unlike step_until, steps no further while it
  // waits
  bool step_and_await(TestGcs& g, const std::function<bool()>& pred) {
    for (int k = 0; k < sim_->control_decimation(); ++k) sim_->step();
    return wait_for([&] {
      g.poll_once(1);
      return pred();
    });
  }

  // uploads a mission of count items with the MISSION_COUNT / MISSION_REQUEST(_INT) /
  // MISSION_ITEM_INT handshake, one exchange at a time, answering each request with item_for(seq);
  // returns the MISSION_ACK type, or -1 when a reply never came
  int upload_mission(TestGcs& g, int count,
                     const std::function<msg::MissionItemInt(int)>& item_for) {
    const std::size_t acks = g.count<msg::MissionAck>();
    // requests come as MISSION_REQUEST until the client has sent an INT item, then as
    // MISSION_REQUEST_INT
    std::size_t reqs = g.count<msg::MissionRequest>(), reqs_int = g.count<msg::MissionRequestInt>();
    msg::MissionCount mc;
    mc.target_system = 1;
    mc.target_component = 1;
    mc.count = static_cast<std::uint16_t>(count);
    g.send(mc);
    for (int exchanges = 0; exchanges <= count; ++exchanges) {
      sync_client(g);
      std::optional<int> seq;
      const bool replied = step_and_await(g, [&] {
        if (g.count<msg::MissionAck>() > acks) return true;
        const auto r = g.all<msg::MissionRequest>();
        const auto ri = g.all<msg::MissionRequestInt>();
        if (r.size() > reqs) seq = r[reqs].seq;
        if (ri.size() > reqs_int) seq = ri[reqs_int].seq;
        return seq.has_value();
      });
      if (!replied) return -1;
      if (g.count<msg::MissionAck>() > acks) return g.last<msg::MissionAck>()->type;
      reqs = g.count<msg::MissionRequest>();
      reqs_int = g.count<msg::MissionRequestInt>();
      msg::MissionItemInt it = item_for(*seq);
      it.target_system = 1;
      it.target_component = 1;
      it.seq = static_cast<std::uint16_t>(*seq);
      g.send(it);
    }
    return -1;  // more requests than items: the handshake went wrong
  }

  // steps until SYS_STATUS reports GPS and pre-arm healthy (GUIDED can be entered then), at most 30
  // s
  void wait_gps_ready(TestGcs& g) {
    constexpr std::uint32_t kPrearm = 0x10000000, kGps = 32;
    ASSERT_TRUE(step_until(
        g,
        [&] {
          const auto s = g.last<msg::SysStatus>();
          return s && (s->onboard_control_sensors_health & kPrearm) &&
                 (s->onboard_control_sensors_health & kGps);
        },
        30.0))
        << "GPS / pre-arm never healthy";
  }

  void step_for(double sim_s) {
    const double end = sim_->time_s() + sim_s;
    while (sim_->time_s() < end) sim_->step();
  }

  // the MAV_CMD name's form of command() below
  int command(TestGcs& g, MavCmd cmd, std::array<float, 7> p = {}, std::uint8_t target_system = 1) {
    return command(g, cmd_id(cmd), p, target_system);
  }
  // sends a COMMAND_LONG and returns its COMMAND_ACK result (-1: no ack within 2 s of sim time); a
  // raw number is for commands MAVLink does not name
  int command(TestGcs& g, std::uint16_t cmd, std::array<float, 7> p = {},
              std::uint8_t target_system = 1) {
    msg::CommandLong c;
    c.command = cmd;
    c.target_system = target_system;
    c.target_component = 1;
    c.param1 = p[0], c.param2 = p[1], c.param3 = p[2], c.param4 = p[3];
    c.param5 = p[4], c.param6 = p[5], c.param7 = p[6];
    const std::size_t acks_before = g.count<msg::CommandAck>();
    g.send(c);
    sync_client(g);
    if (!step_until(
            g, [&] { return g.count<msg::CommandAck>() > acks_before; }, 2.0))
      return -1;
    const auto ack = g.last<msg::CommandAck>();
    EXPECT_EQ(ack->command, cmd);
    return ack->result;
  }

  // waits until every frame the vehicle-0 clients sent (with send()) has been parsed by the
  // endpoint
  void sync_client(TestGcs& g) {
    (void)g;
    std::uint64_t total = 0;
    for (const TestGcs* c : clients_) total += c->sent_frames();
    sync(total + frames_from_unlisted_clients_);
  }

  std::unique_ptr<sim::Simulation> sim_;
  std::unique_ptr<MavlinkServer> server_;
  std::vector<TestGcs*>
      clients_;  // vehicle-0 clients made by connect(); keep them alive in the test
  // frames sent to vehicle 0 by clients not made with connect(): frames_received counts them too,
  // so sync_client() would otherwise return before the listed clients' last frame was parsed
  std::uint64_t frames_from_unlisted_clients_ = 0;
};

}  // namespace uavsim::server::mavlink::testing
