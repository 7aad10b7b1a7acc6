// The socket side of a Vehicle: framing, sending (with the lockstep hold), reading and picking the
// vehicle among what is heard. Behaves like ArduPilot's GCS link (docs/mavlink.md).
#include "mavlink_link.hpp"

#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>

#include "loop_services.hpp"
#include "net.hpp"
#include "uavsim/common/mavlink/codec.hpp"
#include "uavsim/common/mavlink/generated/enums.hpp"
#include "uavsim/common/mavlink/generated/messages.hpp"

namespace uavsim::client {

namespace mav = common::mavlink;
namespace msg = common::mavlink::msg;
using mav::to_underlying;

namespace {

// a vehicle that does not read is dropped rather than buffered without end
constexpr std::size_t kMaxUnsentBytes = 4u << 20;
constexpr std::uint8_t kMavlinkVersion = 3;  // HEARTBEAT.mavlink_version, always 3

// whether a heartbeat comes from an autopilot (not a ground station, gimbal, ADS-B receiver or
// companion computer sharing the link)
bool vehicle_heartbeat(const mav::Frame& f, const msg::Heartbeat& hb) {
  using mav::MavType;
  if (mav::is_one_of<MavType>(
          hb.type, {MavType::Gcs, MavType::Gimbal, MavType::Adsb, MavType::OnboardController})) {
    return false;
  }
  return hb.autopilot != to_underlying(mav::MavAutopilot::Invalid) &&
         f.compid != to_underlying(mav::MavComponent::CompIdGimbal);
}

}  // namespace

MavlinkLink::MavlinkLink(EventLoop& loop, const VehicleConfig& config)
    : loop_(loop), config_(config), target_sysid_(config.target_sysid) {
  // lockstep: `done` names the last seq this link sent, under the simulator's name of the vehicle
  seq_source_ =
      LoopServices(loop_).add_seq_source([this]() -> std::optional<std::pair<std::string, int>> {
        if (!sent_any_ || fd_ < 0) return std::nullopt;
        std::string key = config_.sim_vehicle;
        if (key.empty()) key = std::to_string(std::max(0, static_cast<int>(target_sysid_) - 1));
        return std::make_pair(key, static_cast<int>(last_seq_));
      });
  output_flusher_ = LoopServices(loop_).add_output_flusher([this] { release_held(); });
}

MavlinkLink::~MavlinkLink() {
  on_closed_ = nullptr;  // the units it would tell are gone
  close(nullptr);
  LoopServices(loop_).remove_seq_source(seq_source_);
  LoopServices(loop_).remove_output_flusher(output_flusher_);
}

Result<void> MavlinkLink::open(const std::string& address, double timeout_s) {
  close(nullptr);
  const auto where = net::parse_link_address(address);
  if (!where) {
    return Result<void>::fail(
        Error::kInvalidArgument,
        "bad vehicle address '" + address + "' (tcp:HOST:PORT, udp:HOST:PORT or udpin:ADDR:PORT)");
  }
  address_ = address;
  using Kind = net::LinkAddress::Kind;
  udp_ = where->kind != Kind::kTcp;
  udp_peer_ = where->kind == Kind::kUdp;
  auto fd = udp_ ? net::udp_open(where->host, where->port, where->kind == Kind::kUdpIn)
                 : net::tcp_connect(where->host, where->port, std::min(timeout_s, 30.0));
  if (!fd) return Result<void>(fd.error());
  fd_ = *fd;
  parser_.reset();
  target_sysid_ = config_.target_sysid;
  if (auto w =
          loop_.watch_fd(fd_, EventLoop::kReadable, [this](std::uint32_t what) { on_io(what); });
      !w) {
    close(nullptr);
    return w;
  }
  send_heartbeat();
  heartbeat_timer_ = loop_.call_every(config_.heartbeat_period_s, [this] { send_heartbeat(); });
  return {};
}

void MavlinkLink::close(const char* why) {
  const bool was_open = fd_ >= 0;
  if (was_open) {
    loop_.unwatch_fd(fd_);
    ::close(fd_);
    fd_ = -1;
  }
  if (was_open && why != nullptr) {
    std::fprintf(stderr, "uavsim client: %s: link closed: %s\n", address_.c_str(), why);
  }
  out_.clear();
  held_out_.clear();
  if (heartbeat_timer_ != 0) loop_.cancel(heartbeat_timer_);
  heartbeat_timer_ = 0;
  if (on_closed_) on_closed_(why);
}

bool MavlinkLink::send_payload(const mav::MessageInfo& info,
                               std::span<const std::uint8_t> full_payload) {
  if (fd_ < 0) return false;
  // a udpin link cannot send before the vehicle has been heard from (nor count the frame as sent:
  // lockstep waits for the sequence numbers a link really sent)
  if (udp_ && !udp_peer_) return false;
  mav::FrameHeader h;
  h.sysid = config_.gcs_sysid;
  h.compid = config_.gcs_compid;
  h.seq = seq_;
  mav::EncodedFrame f;
  f.size = mav::encode_frame(h, info, full_payload, f.bytes);
  if (f.empty()) return false;
  last_seq_ = seq_++;
  sent_any_ = true;
  // pipelined lockstep: what is sent during a tick's work goes out at the next tick (release_held)
  std::string& to = LoopServices(loop_).outputs_held() ? held_out_ : out_;
  to.append(reinterpret_cast<const char*>(f.bytes.data()), f.size);
  if (out_.size() + held_out_.size() > kMaxUnsentBytes) {
    close("the vehicle does not read (4 MiB unsent)");
    return false;
  }
  if (&to == &out_) flush();
  return fd_ >= 0;
}

void MavlinkLink::flush() {
  if (udp_) {
    // one datagram per call (frames are flushed as they are queued); a lost datagram is lost, as on
    // a radio link, and a udpin link drops what it sends before the vehicle has been heard from
    if (udp_peer_ && !out_.empty()) {
      (void)::send(fd_, out_.data(), out_.size(), MSG_NOSIGNAL | MSG_DONTWAIT);
    }
    out_.clear();
    return;
  }
  while (!out_.empty() && fd_ >= 0) {
    const ssize_t n = ::send(fd_, out_.data(), out_.size(), MSG_NOSIGNAL | MSG_DONTWAIT);
    if (n > 0) {
      out_.erase(0, static_cast<std::size_t>(n));
      continue;
    }
    if (n < 0 && errno == EINTR) continue;
    if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) break;
    close(std::strerror(errno));
    return;
  }
  if (fd_ >= 0) {
    (void)loop_.modify_fd(fd_, EventLoop::kReadable | (out_.empty() ? 0u : EventLoop::kWritable));
  }
}

// pipelined lockstep, at a tick before `done`: the frames held since the last tick go out
void MavlinkLink::release_held() {
  if (held_out_.empty()) return;
  out_ += held_out_;
  held_out_.clear();
  flush();
}

void MavlinkLink::on_io(std::uint32_t what) {
  if (what & EventLoop::kWritable) flush();
  if (fd_ < 0 || !(what & EventLoop::kReadable)) return;
  std::uint8_t buf[16384];
  const auto feed = [&](ssize_t n) {
    parser_.feed({buf, static_cast<std::size_t>(n)}, [&](const mav::Frame& f) { handle(f); });
  };
  for (;;) {
    if (udp_) {
      sockaddr_in from{};
      socklen_t from_len = sizeof(from);
      const ssize_t n = ::recvfrom(fd_, buf, sizeof(buf), MSG_DONTWAIT,
                                   reinterpret_cast<sockaddr*>(&from), &from_len);
      if (n < 0 && errno == EINTR) continue;
      if (n < 0) return;  // EAGAIN; or ICMP port unreachable (nobody there yet): the link stays
      // udpin: the first sender is the vehicle; from now on only it is heard and answered
      if (!udp_peer_ && ::connect(fd_, reinterpret_cast<sockaddr*>(&from), from_len) == 0) {
        udp_peer_ = true;
      }
      feed(n);
      if (fd_ < 0) return;
      continue;
    }
    const ssize_t n = ::recv(fd_, buf, sizeof(buf), MSG_DONTWAIT);
    if (n > 0) {
      feed(n);
      if (fd_ < 0) return;
      continue;
    }
    if (n == 0) {
      close("the vehicle closed the connection");
      return;
    }
    if (errno == EINTR) continue;
    if (errno != EAGAIN && errno != EWOULDBLOCK) close(std::strerror(errno));
    return;
  }
}

// the first autopilot heard becomes the vehicle (unless config.target_sysid names one); only its
// frames reach the units
void MavlinkLink::handle(const mav::Frame& f) {
  if (f.msgid == msg::Heartbeat::kId) {
    if (!vehicle_heartbeat(f, msg::Heartbeat::decode(f.payload.data()))) return;
    if (target_sysid_ == 0) target_sysid_ = f.sysid;
    if (f.sysid != target_sysid_) return;
    target_compid_ = f.compid;
  }
  if (target_sysid_ == 0 || f.sysid != target_sysid_) return;
  dispatch(f);
}

void MavlinkLink::send_heartbeat() {
  msg::Heartbeat hb;
  hb.type = to_underlying(mav::MavType::Gcs);
  hb.autopilot = to_underlying(mav::MavAutopilot::Invalid);
  hb.base_mode = 0;
  hb.custom_mode = 0;
  hb.system_status = to_underlying(mav::MavState::Active);
  hb.mavlink_version = kMavlinkVersion;
  send(hb);
}

}  // namespace uavsim::client
