// Vehicle proxy: MAVLink over TCP with our codec (uavsim/common/mavlink), per ArduCopter's
// behaviour on the wire, which the server's vehicles reproduce (docs/mavlink.md). The only client
// source that speaks MAVLink.
#include "uavsim/client/vehicle.hpp"

#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <deque>
#include <map>
#include <sstream>

#include "loop_services.hpp"
#include "net.hpp"
#include "uavsim/common/mavlink/codec.hpp"
#include "uavsim/common/mavlink/generated/enums.hpp"
#include "uavsim/common/mavlink/generated/messages.hpp"
#include "uavsim/common/mavlink/mission_item.hpp"
#include "uavsim/common/mavlink/parser.hpp"

namespace uavsim::client {

namespace mav = common::mavlink;
namespace msg = common::mavlink::msg;
using mav::MavCmd;
using mav::MavFrame;
using mav::MavResult;
using mav::to_underlying;

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr std::uint32_t kPrearmBit = 0x10000000;
constexpr std::uint16_t kEkfPredPosHorizAbs = 512;
constexpr std::uint16_t kEkfPosHorizAbs = 16;
// SET_POSITION_TARGET type masks: what a setpoint sets, everything else ignored
constexpr std::uint16_t ignore(std::initializer_list<mav::PositionTargetTypemask> bits) {
  std::uint16_t m = 0;
  for (auto b : bits) m = static_cast<std::uint16_t>(m | to_underlying(b));
  return m;
}
using Ignore = mav::PositionTargetTypemask;
constexpr std::uint16_t kIgnoreVel = ignore({Ignore::VxIgnore, Ignore::VyIgnore, Ignore::VzIgnore});
constexpr std::uint16_t kIgnorePos = ignore({Ignore::XIgnore, Ignore::YIgnore, Ignore::ZIgnore});
constexpr std::uint16_t kIgnoreAcc = ignore({Ignore::AxIgnore, Ignore::AyIgnore, Ignore::AzIgnore});
constexpr std::uint16_t kIgnoreYaw = ignore({Ignore::YawIgnore});
constexpr std::uint16_t kIgnoreYawRate = ignore({Ignore::YawRateIgnore});
constexpr std::uint16_t kMaskPos = kIgnoreVel | kIgnoreAcc | kIgnoreYaw | kIgnoreYawRate;  // 3576
constexpr std::uint16_t kMaskPosYaw = kIgnoreVel | kIgnoreAcc | kIgnoreYawRate;            // 2552
constexpr std::uint16_t kMaskVel = kIgnorePos | kIgnoreAcc | kIgnoreYaw | kIgnoreYawRate;  // 3527
constexpr std::uint16_t kMaskVelYaw = kIgnorePos | kIgnoreAcc | kIgnoreYawRate;            // 2503
constexpr std::uint16_t kMaskVelYawRate = kIgnorePos | kIgnoreAcc | kIgnoreYaw;            // 1479
static_assert(kMaskPos == 3576 && kMaskPosYaw == 2552 && kMaskVel == 3527 && kMaskVelYaw == 2503 &&
              kMaskVelYawRate == 1479);

constexpr std::uint16_t mav_command(MavCmd c) { return static_cast<std::uint16_t>(to_underlying(c)); }
constexpr std::uint8_t mav_frame(MavFrame f) { return static_cast<std::uint8_t>(to_underlying(f)); }
constexpr std::uint8_t kMissionTypeMission = to_underlying(mav::MavMissionType::Mission);

const char* mav_result_name(int r) {
  switch (static_cast<MavResult>(r)) {
    case MavResult::Accepted: return "ACCEPTED";
    case MavResult::TemporarilyRejected: return "TEMPORARILY_REJECTED";
    case MavResult::Denied: return "DENIED";
    case MavResult::Unsupported: return "UNSUPPORTED";
    case MavResult::Failed: return "FAILED";
    case MavResult::InProgress: return "IN_PROGRESS";
    case MavResult::Cancelled: return "CANCELLED";
    default: return "UNKNOWN";
  }
}

const char* mission_result_name(int r) {
  static const char* names[] = {"ACCEPTED", "ERROR", "UNSUPPORTED_FRAME", "UNSUPPORTED", "NO_SPACE", "INVALID",
                                "INVALID_PARAM1", "INVALID_PARAM2", "INVALID_PARAM3", "INVALID_PARAM4",
                                "INVALID_PARAM5_X", "INVALID_PARAM6_Y", "INVALID_PARAM7", "INVALID_SEQUENCE",
                                "DENIED", "OPERATION_CANCELLED"};
  return r >= 0 && r < 16 ? names[r] : "UNKNOWN";
}

std::string command_name(std::uint16_t c) {
  switch (static_cast<MavCmd>(c)) {
    case MavCmd::NavWaypoint: return "NAV_WAYPOINT";
    case MavCmd::NavLoiterUnlim: return "NAV_LOITER_UNLIM";
    case MavCmd::NavReturnToLaunch: return "NAV_RETURN_TO_LAUNCH";
    case MavCmd::NavLand: return "NAV_LAND";
    case MavCmd::NavTakeoff: return "NAV_TAKEOFF";
    case MavCmd::ConditionYaw: return "CONDITION_YAW";
    case MavCmd::DoSetMode: return "DO_SET_MODE";
    case MavCmd::DoMountControl: return "DO_MOUNT_CONTROL";
    case MavCmd::MissionStart: return "MISSION_START";
    case MavCmd::ComponentArmDisarm: return "COMPONENT_ARM_DISARM";
    case MavCmd::GetHomePosition: return "GET_HOME_POSITION";
    case MavCmd::SetMessageInterval: return "SET_MESSAGE_INTERVAL";
    case MavCmd::RequestMessage: return "REQUEST_MESSAGE";
    default: return "MAV_CMD " + std::to_string(c);
  }
}

Error error_of_mav_result(int r) {
  switch (static_cast<MavResult>(r)) {
    case MavResult::TemporarilyRejected: return Error::kTemporarilyRejected;
    case MavResult::Denied: return Error::kDenied;
    case MavResult::Unsupported: return Error::kUnsupported;
    case MavResult::Cancelled: return Error::kCancelled;
    default: return Error::kFailed;
  }
}

std::int32_t e7(double deg) { return static_cast<std::int32_t>(std::llround(deg * 1e7)); }

}  // namespace

const char* error_name(Error e) {
  switch (e) {
    case Error::kTimeout: return "timeout";
    case Error::kConnectionRefused: return "connection refused";
    case Error::kNotConnected: return "not connected";
    case Error::kConnectionLost: return "connection lost";
    case Error::kDenied: return "denied";
    case Error::kFailed: return "failed";
    case Error::kUnsupported: return "unsupported";
    case Error::kTemporarilyRejected: return "temporarily rejected";
    case Error::kCancelled: return "cancelled";
    case Error::kNotReady: return "not ready";
    case Error::kInvalidArgument: return "invalid argument";
    case Error::kIo: return "I/O error";
    case Error::kProtocol: return "protocol error";
  }
  return "?";
}

void abort_on_failure(const Failure& f) {
  std::fprintf(stderr, "uavsim client: value() of a failed Result: %s: %s\n", error_name(f.code), f.message.c_str());
  std::abort();
}

const char* mode_name(FlightMode m) {
  switch (m) {
    case FlightMode::kStabilize: return "STABILIZE";
    case FlightMode::kAcro: return "ACRO";
    case FlightMode::kAltHold: return "ALT_HOLD";
    case FlightMode::kAuto: return "AUTO";
    case FlightMode::kGuided: return "GUIDED";
    case FlightMode::kLoiter: return "LOITER";
    case FlightMode::kRtl: return "RTL";
    case FlightMode::kCircle: return "CIRCLE";
    case FlightMode::kLand: return "LAND";
    case FlightMode::kDrift: return "DRIFT";
    case FlightMode::kSport: return "SPORT";
    case FlightMode::kFlip: return "FLIP";
    case FlightMode::kAutotune: return "AUTOTUNE";
    case FlightMode::kPosHold: return "POSHOLD";
    case FlightMode::kBrake: return "BRAKE";
    case FlightMode::kThrow: return "THROW";
    case FlightMode::kAvoidAdsb: return "AVOID_ADSB";
    case FlightMode::kGuidedNoGps: return "GUIDED_NOGPS";
    case FlightMode::kSmartRtl: return "SMART_RTL";
    case FlightMode::kFlowHold: return "FLOWHOLD";
    case FlightMode::kFollow: return "FOLLOW";
    case FlightMode::kZigZag: return "ZIGZAG";
    case FlightMode::kSystemId: return "SYSTEMID";
    case FlightMode::kAutorotate: return "AUTOROTATE";
    case FlightMode::kAutoRtl: return "AUTO_RTL";
    case FlightMode::kTurtle: return "TURTLE";
  }
  return "UNKNOWN";
}

MissionItem MissionItem::takeoff(double rel_alt_m) {
  MissionItem m;
  m.command = mav_command(MavCmd::NavTakeoff);
  m.alt_m = static_cast<float>(rel_alt_m);
  return m;
}
MissionItem MissionItem::waypoint(double lat_deg, double lon_deg, double rel_alt_m, double hold_s) {
  MissionItem m;
  m.command = mav_command(MavCmd::NavWaypoint);
  m.param1 = static_cast<float>(hold_s);
  m.lat_deg = lat_deg;
  m.lon_deg = lon_deg;
  m.alt_m = static_cast<float>(rel_alt_m);
  return m;
}
MissionItem MissionItem::land() {
  MissionItem m;
  m.command = mav_command(MavCmd::NavLand);
  return m;
}
MissionItem MissionItem::rtl() {
  MissionItem m;
  m.command = mav_command(MavCmd::NavReturnToLaunch);
  return m;
}

// ---------------------------------------------------------------------------------------------------- Impl

struct Vehicle::Impl {
  EventLoop& loop;
  VehicleConfig config;
  int fd = -1;
  bool link_up = false;
  std::string address;
  bool udp = false;       // a UDP link: datagrams, no end of stream
  bool udp_peer = false;  // the UDP socket is connected to the vehicle (udpin: once it has sent)
  mav::Parser parser;
  std::string out;  // bytes not yet accepted by the socket
  std::uint8_t seq = 0;
  bool sent_any = false;
  std::uint8_t last_seq = 0;
  std::uint8_t target_sysid = 0;
  std::uint8_t target_compid = 1;

  Telemetry tm;
  std::function<void(const Telemetry&)> on_telemetry;
  std::function<void(int, const std::string&)> on_status;
  std::vector<std::string> texts;

  TimerId heartbeat_timer = 0;
  TimerId home_timer = 0;
  TimerId resend_timer = 0;
  std::optional<msg::SetPositionTargetLocalNed> resend_setpoint;
  std::uint64_t seq_source = 0;
  std::uint64_t output_flusher = 0;
  std::string held_out;  // pipelined lockstep: frames sent during this tick's work (send, release_held)

  std::map<std::uint16_t, msg::CommandAck> acks;
  // commands sent with command_async(), by id: retried on silence like command(); `done` runs (posted
  // to the loop) with the final answer
  struct AsyncCommand {
    std::array<float, 7> params{};
    int attempt = 0;
    TimerId retry = 0;
    std::function<void(Result<void>)> done;
  };
  std::map<std::uint16_t, AsyncCommand> async_commands;
  struct ParamSeen {
    float value = 0;
    std::uint8_t type = to_underlying(mav::MavParamType::Real32);
    std::uint64_t count = 0;
  };
  std::map<std::string, ParamSeen> params;

  // mission upload in progress
  bool mission_active = false;
  std::vector<msg::MissionItemInt> mission;
  std::optional<int> mission_ack;
  int mission_requests = 0;

  Impl(EventLoop& l, VehicleConfig c) : loop(l), config(std::move(c)) {}

  // ------------------------------------------------------------------ link
  void close_link(const char* why) {
    if (fd >= 0) {
      loop.unwatch_fd(fd);
      ::close(fd);
      fd = -1;
    }
    if (link_up && why != nullptr) std::fprintf(stderr, "uavsim client: %s: link closed: %s\n", address.c_str(), why);
    link_up = false;
    out.clear();
    held_out.clear();
    for (TimerId* t : {&heartbeat_timer, &home_timer, &resend_timer}) {
      if (*t != 0) loop.cancel(*t);
      *t = 0;
    }
    resend_setpoint.reset();
    fail_all_async(why != nullptr ? std::string("the link was lost: ") + why : "the link was closed");
    mission_active = false;
  }

  void flush() {
    if (udp) {
      // one datagram per call (frames are flushed as they are queued); a lost datagram is lost, as on a
      // radio link, and a udpin link drops what it sends before the vehicle has been heard from
      if (udp_peer && !out.empty()) (void)::send(fd, out.data(), out.size(), MSG_NOSIGNAL | MSG_DONTWAIT);
      out.clear();
      return;
    }
    while (!out.empty() && fd >= 0) {
      const ssize_t n = ::send(fd, out.data(), out.size(), MSG_NOSIGNAL | MSG_DONTWAIT);
      if (n > 0) {
        out.erase(0, static_cast<std::size_t>(n));
        continue;
      }
      if (n < 0 && errno == EINTR) continue;
      if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) break;
      close_link(std::strerror(errno));
      return;
    }
    if (fd >= 0) (void)loop.modify_fd(fd, EventLoop::kReadable | (out.empty() ? 0u : EventLoop::kWritable));
  }

  template <class Msg>
  bool send(const Msg& m) {
    if (fd < 0) return false;
    // a udpin link cannot send before the vehicle has been heard from (nor count the frame as sent:
    // lockstep waits for the sequence numbers a link really sent)
    if (udp && !udp_peer) return false;
    mav::FrameHeader h;
    h.sysid = config.gcs_sysid;
    h.compid = config.gcs_compid;
    h.seq = seq;
    const mav::EncodedFrame f = mav::encode(h, m);
    if (f.empty()) return false;
    last_seq = seq++;
    sent_any = true;
    // pipelined lockstep: what is sent during a tick's work goes out at the next tick (release_held)
    std::string& to = LoopServices(loop).outputs_held() ? held_out : out;
    to.append(reinterpret_cast<const char*>(f.bytes.data()), f.size);
    if (out.size() + held_out.size() > (4u << 20)) {
      close_link("the vehicle does not read (4 MiB unsent)");
      return false;
    }
    if (&to == &out) flush();
    return fd >= 0;
  }

  // pipelined lockstep, at a tick before `done`: the frames held since the last tick go out
  void release_held() {
    if (held_out.empty()) return;
    out += held_out;
    held_out.clear();
    flush();
  }

  void on_io(std::uint32_t what) {
    if (what & EventLoop::kWritable) flush();
    if (fd < 0 || !(what & EventLoop::kReadable)) return;
    std::uint8_t buf[16384];
    for (;;) {
      if (udp) {
        sockaddr_in from{};
        socklen_t from_len = sizeof(from);
        const ssize_t n = ::recvfrom(fd, buf, sizeof(buf), MSG_DONTWAIT, reinterpret_cast<sockaddr*>(&from), &from_len);
        if (n < 0 && errno == EINTR) continue;
        if (n < 0) return;  // EAGAIN; or ICMP port unreachable (nobody there yet): the link stays
        // udpin: the first sender is the vehicle; from now on only it is heard and answered
        if (!udp_peer && ::connect(fd, reinterpret_cast<sockaddr*>(&from), from_len) == 0) udp_peer = true;
        parser.feed({buf, static_cast<std::size_t>(n)}, [&](const mav::Frame& f) { handle(f); });
        if (fd < 0) return;
        continue;
      }
      const ssize_t n = ::recv(fd, buf, sizeof(buf), MSG_DONTWAIT);
      if (n > 0) {
        parser.feed({buf, static_cast<std::size_t>(n)}, [&](const mav::Frame& f) { handle(f); });
        if (fd < 0) return;
        continue;
      }
      if (n == 0) {
        close_link("the vehicle closed the connection");
        return;
      }
      if (errno == EINTR) continue;
      if (errno != EAGAIN && errno != EWOULDBLOCK) close_link(std::strerror(errno));
      return;
    }
  }

  void send_heartbeat() {
    msg::Heartbeat hb;
    hb.type = to_underlying(mav::MavType::Gcs);
    hb.autopilot = to_underlying(mav::MavAutopilot::Invalid);
    hb.base_mode = 0;
    hb.custom_mode = 0;
    hb.system_status = to_underlying(mav::MavState::Active);
    hb.mavlink_version = 3;
    send(hb);
  }

  void request_streams() {
    const auto rate = static_cast<std::uint16_t>(std::clamp(std::lround(config.telemetry_rate_hz), 1L, 50L));
    using Stream = mav::MavDataStream;
    const std::pair<Stream, std::uint16_t> groups[] = {
        {Stream::ExtendedStatus, 2}, {Stream::Position, rate}, {Stream::Extra1, rate}, {Stream::Extra2, 4},
        {Stream::Extra3, 2}};
    for (const auto& [id, hz] : groups) {
      msg::RequestDataStream r;
      r.target_system = target_sysid;
      r.target_component = target_compid;
      r.req_stream_id = static_cast<std::uint8_t>(to_underlying(id));
      r.req_message_rate = hz;
      r.start_stop = 1;
      send(r);
    }
    // not in any stream group: ask for them by interval (acks are not awaited)
    const std::pair<std::uint32_t, double> intervals[] = {{msg::HomePosition::kId, 1.0},
                                                           {msg::ExtendedSysState::kId, 1.0},
                                                           {msg::GpsGlobalOrigin::kId, 5.0},
                                                           {msg::MountStatus::kId, 0.5}};
    for (const auto& [id, period] : intervals) {
      msg::CommandLong c;
      c.target_system = target_sysid;
      c.target_component = target_compid;
      c.command = mav_command(MavCmd::SetMessageInterval);
      c.param1 = static_cast<float>(id);
      c.param2 = static_cast<float>(period * 1e6);
      send(c);
    }
  }

  // ------------------------------------------------------------------ incoming
  static bool vehicle_heartbeat(const mav::Frame& f, const msg::Heartbeat& hb) {
    using mav::MavType;
    if (mav::is_one_of<MavType>(hb.type,
                                {MavType::Gcs, MavType::Gimbal, MavType::Adsb, MavType::OnboardController})) {
      return false;
    }
    return hb.autopilot != to_underlying(mav::MavAutopilot::Invalid) &&
           f.compid != to_underlying(mav::MavComponent::CompIdGimbal);
  }

  void handle(const mav::Frame& f) {
    if (f.msgid == msg::Heartbeat::kId) {
      const auto hb = msg::Heartbeat::decode(f.payload.data());
      if (!vehicle_heartbeat(f, hb)) return;
      if (target_sysid == 0) target_sysid = f.sysid;
      if (f.sysid != target_sysid) return;
      target_compid = f.compid;
      tm.sysid = f.sysid;
      tm.heartbeat_seen = true;
      tm.last_heartbeat_time = loop.now();
      tm.custom_mode = hb.custom_mode;
      tm.mode = static_cast<FlightMode>(hb.custom_mode);
      tm.armed = (hb.base_mode & 128) != 0;
      tm.system_status = hb.system_status;
      // stale velocity re-sends must not resume when someone switches back to GUIDED later
      if (tm.mode != FlightMode::kGuided && resend_timer != 0) {
        loop.cancel(resend_timer);
        resend_timer = 0;
        resend_setpoint.reset();
      }
      notify();
      return;
    }
    if (target_sysid == 0 || f.sysid != target_sysid) return;
    switch (f.msgid) {
      case msg::SysStatus::kId: {
        const auto m = msg::SysStatus::decode(f.payload.data());
        tm.sensors_health = m.onboard_control_sensors_health;
        tm.prearm_ok = (m.onboard_control_sensors_health & kPrearmBit) != 0;
        tm.battery_voltage_v = m.voltage_battery / 1000.0;
        tm.battery_current_a = m.current_battery / 100.0;
        tm.battery_remaining_pct = m.battery_remaining;
        break;
      }
      case msg::GpsRawInt::kId: {
        const auto m = msg::GpsRawInt::decode(f.payload.data());
        tm.gps_fix_type = m.fix_type;
        tm.gps_satellites = m.satellites_visible;
        tm.gps_hdop = m.eph / 100.0;
        tm.gps_position = {m.lat / 1e7, m.lon / 1e7, m.alt / 1000.0};
        break;
      }
      case msg::LocalPositionNed::kId: {
        const auto m = msg::LocalPositionNed::decode(f.payload.data());
        tm.vehicle_time_s = m.time_boot_ms / 1000.0;
        tm.has_local_position = true;
        tm.position_ned_m = {m.x, m.y, m.z};
        tm.velocity_ned_m_s = {m.vx, m.vy, m.vz};
        tm.position_enu_m = enu_from_ned(tm.position_ned_m);
        tm.velocity_enu_m_s = enu_from_ned(tm.velocity_ned_m_s);
        break;
      }
      case msg::GlobalPositionInt::kId: {
        const auto m = msg::GlobalPositionInt::decode(f.payload.data());
        tm.has_global_position = true;
        tm.position = {m.lat / 1e7, m.lon / 1e7, m.alt / 1000.0};
        tm.relative_alt_m = m.relative_alt / 1000.0;
        if (m.hdg != 65535) tm.heading_deg = m.hdg / 100.0;
        break;
      }
      case msg::Attitude::kId: {
        const auto m = msg::Attitude::decode(f.payload.data());
        tm.has_attitude = true;
        tm.roll_rad = m.roll;
        tm.pitch_rad = m.pitch;
        tm.yaw_rad = m.yaw;
        tm.body_rates_rad_s = {m.rollspeed, m.pitchspeed, m.yawspeed};
        break;
      }
      case msg::BatteryStatus::kId: {
        const auto m = msg::BatteryStatus::decode(f.payload.data());
        if (m.current_consumed >= 0) tm.battery_consumed_mah = m.current_consumed;
        break;
      }
      case msg::ExtendedSysState::kId:
        tm.landed = static_cast<LandedState>(msg::ExtendedSysState::decode(f.payload.data()).landed_state);
        break;
      case msg::EkfStatusReport::kId: {
        const auto m = msg::EkfStatusReport::decode(f.payload.data());
        tm.ekf_flags = m.flags;
        tm.ekf_ok = (m.flags & kEkfPredPosHorizAbs) != 0 || (m.flags & kEkfPosHorizAbs) != 0;
        break;
      }
      case msg::HomePosition::kId: {
        const auto m = msg::HomePosition::decode(f.payload.data());
        tm.home_set = true;
        tm.home = {m.latitude / 1e7, m.longitude / 1e7, m.altitude / 1000.0};
        tm.home_ned_m = {m.x, m.y, m.z};
        break;
      }
      case msg::GpsGlobalOrigin::kId: {
        const auto m = msg::GpsGlobalOrigin::decode(f.payload.data());
        tm.origin_set = true;
        tm.origin = {m.latitude / 1e7, m.longitude / 1e7, m.altitude / 1000.0, 0.0};
        break;
      }
      case msg::MountStatus::kId: {
        const auto m = msg::MountStatus::decode(f.payload.data());
        tm.has_gimbal = true;
        tm.gimbal_pitch_deg = m.pointing_a / 100.0;
        tm.gimbal_roll_deg = m.pointing_b / 100.0;
        tm.gimbal_yaw_deg = m.pointing_c / 100.0;
        break;
      }
      case msg::MissionCurrent::kId:
        tm.mission_current = msg::MissionCurrent::decode(f.payload.data()).seq;
        break;
      case msg::MissionItemReached::kId:
        tm.mission_last_reached = msg::MissionItemReached::decode(f.payload.data()).seq;
        break;
      case msg::CommandAck::kId: {
        const auto m = msg::CommandAck::decode(f.payload.data());
        if (m.target_system != 0 && m.target_system != config.gcs_sysid) return;
        acks[m.command] = m;
        on_async_ack(m);
        return;
      }
      case msg::ParamValue::kId: {
        const auto m = msg::ParamValue::decode(f.payload.data());
        ParamSeen& p = params[std::string(mav::get_string(m.param_id))];
        p.value = m.param_value;
        p.type = m.param_type;
        ++p.count;
        return;
      }
      case msg::MissionRequestInt::kId:
      case msg::MissionRequest::kId: {
        // both carry (seq, target_system, target_component, mission_type) in the same layout
        const auto m = msg::MissionRequestInt::decode(f.payload.data());
        if (!mission_active || m.mission_type != kMissionTypeMission) return;
        if (m.seq >= mission.size()) return;
        ++mission_requests;
        if (f.msgid == msg::MissionRequestInt::kId) {
          send(mission[m.seq]);
        } else {
          send(mav::legacy_mission_item(mission[m.seq]));
        }
        return;
      }
      case msg::MissionAck::kId: {
        const auto m = msg::MissionAck::decode(f.payload.data());
        if (mission_active && m.mission_type == kMissionTypeMission) mission_ack = m.type;
        return;
      }
      case msg::Statustext::kId: {
        const auto m = msg::Statustext::decode(f.payload.data());
        std::string text(mav::get_string(m.text));
        texts.push_back(text);
        if (texts.size() > 100) texts.erase(texts.begin());
        if (on_status) on_status(m.severity, text);
        return;
      }
      default:
        return;
    }
    notify();
  }

  void notify() {
    if (on_telemetry) on_telemetry(tm);
  }

  // ------------------------------------------------------------------ outgoing helpers
  Result<void> need_link() const {
    if (fd >= 0 && link_up) return {};
    return Result<void>::fail(Error::kNotConnected, "not connected to a vehicle" + (address.empty() ? "" : " (" + address + ")"));
  }

  // one COMMAND_LONG of a command's attempt (confirmation = the attempt number), for command() and
  // command_async() alike
  msg::CommandLong command_long(std::uint16_t cmd, const std::array<float, 7>& p, int attempt) const {
    msg::CommandLong c;
    c.target_system = target_sysid;
    c.target_component = target_compid;
    c.command = cmd;
    c.confirmation = static_cast<std::uint8_t>(std::min(attempt, 255));
    c.param1 = p[0], c.param2 = p[1], c.param3 = p[2], c.param4 = p[3];
    c.param5 = p[4], c.param6 = p[5], c.param7 = p[6];
    return c;
  }
  // the outcome of a final COMMAND_ACK (any result but IN_PROGRESS)
  static Result<void> ack_outcome(std::uint16_t cmd, int result) {
    if (result == static_cast<int>(to_underlying(MavResult::Accepted))) return {};
    return Result<void>::fail(error_of_mav_result(result),
                              command_name(cmd) + " refused by the vehicle: MAV_RESULT_" + mav_result_name(result) +
                                  " (" + std::to_string(result) + ")",
                              result);
  }
  static Result<void> link_lost(std::uint16_t cmd) {
    return Result<void>::fail(Error::kConnectionLost, command_name(cmd) + ": the link was lost");
  }
  Result<void> no_ack(std::uint16_t cmd) const {
    std::ostringstream os;
    os << "no COMMAND_ACK for " << command_name(cmd) << " after " << std::max(1, config.command_attempts)
       << " attempt(s) of " << config.command_timeout_s << " s";
    return Result<void>::fail(Error::kTimeout, os.str());
  }

  Result<void> command(std::uint16_t cmd, const std::array<float, 7>& p) {
    loop.assert_in_loop_thread();
    if (auto r = need_link(); !r) return r;
    const int attempts = std::max(1, config.command_attempts);
    for (int attempt = 0; attempt < attempts; ++attempt) {
      acks.erase(cmd);
      if (!send(command_long(cmd, p, attempt))) break;
      for (;;) {
        auto w = loop.run_until([&] { return acks.count(cmd) > 0 || fd < 0; }, config.command_timeout_s,
                                "COMMAND_ACK");
        if (fd < 0) return link_lost(cmd);
        if (!w && w.code() == Error::kConnectionLost) return w;
        auto it = acks.find(cmd);
        if (it == acks.end()) break;  // silence: try again
        const int result = it->second.result;
        if (result == static_cast<int>(to_underlying(MavResult::InProgress))) {  // the final ack follows
          acks.erase(it);
          continue;
        }
        return ack_outcome(cmd, result);
      }
    }
    if (auto r = need_link(); !r) return link_lost(cmd);
    return no_ack(cmd);
  }

  // ------------------------------------------------------------------ non-blocking commands
  void command_async(std::uint16_t cmd, const std::array<float, 7>& p, std::function<void(Result<void>)> done) {
    loop.assert_in_loop_thread();
    if (auto r = need_link(); !r) {
      if (done) loop.post([done = std::move(done), r] { done(r); });
      return;
    }
    finish_async(cmd, Result<void>::fail(Error::kCancelled, command_name(cmd) + ": replaced by a newer one"));
    AsyncCommand& a = async_commands[cmd];
    a.params = p;
    a.done = std::move(done);
    send_async(cmd);
  }

  void send_async(std::uint16_t cmd) {
    const AsyncCommand& a = async_commands.at(cmd);
    if (!send(command_long(cmd, a.params, a.attempt))) {
      finish_async(cmd, link_lost(cmd));
      return;
    }
    arm_async_retry(cmd);
  }

  void arm_async_retry(std::uint16_t cmd) {
    AsyncCommand& a = async_commands.at(cmd);
    if (a.retry != 0) loop.cancel(a.retry);
    a.retry = loop.call_after(config.command_timeout_s, [this, cmd] {
      auto it = async_commands.find(cmd);
      if (it == async_commands.end()) return;
      it->second.retry = 0;
      if (++it->second.attempt < std::max(1, config.command_attempts)) {
        send_async(cmd);
        return;
      }
      finish_async(cmd, no_ack(cmd));
    });
  }

  void on_async_ack(const msg::CommandAck& m) {
    if (async_commands.count(m.command) == 0) return;
    if (m.result == to_underlying(MavResult::InProgress)) {  // the final ack follows
      arm_async_retry(m.command);
      return;
    }
    finish_async(m.command, ack_outcome(m.command, m.result));
  }

  // ends a pending non-blocking command (nothing when none): its done runs on the loop, after the
  // caller's own work (a done that sends the next command does not nest inside the I/O handler)
  void finish_async(std::uint16_t cmd, Result<void> r) {
    auto it = async_commands.find(cmd);
    if (it == async_commands.end()) return;
    if (it->second.retry != 0) loop.cancel(it->second.retry);
    auto done = std::move(it->second.done);
    async_commands.erase(it);
    if (done) loop.post([done = std::move(done), r = std::move(r)] { done(r); });
  }

  void fail_all_async(const std::string& why) {
    while (!async_commands.empty()) {
      const std::uint16_t cmd = async_commands.begin()->first;
      finish_async(cmd, Result<void>::fail(Error::kConnectionLost, command_name(cmd) + ": " + why));
    }
  }

  // DO_SET_MODE (176) and COMPONENT_ARM_DISARM (400) arming, blocking or not
  static std::array<float, 7> set_mode_params(FlightMode mode) {
    return {1.0f, static_cast<float>(static_cast<std::uint32_t>(mode)), 0, 0, 0, 0, 0};
  }
  static std::array<float, 7> arm_params(bool force) { return {1.0f, force ? 2989.0f : 0.0f, 0, 0, 0, 0, 0}; }
  // the mode the vehicle accepted, until its next heartbeat says it
  void note_mode(FlightMode mode) {
    tm.mode = mode;
    tm.custom_mode = static_cast<std::uint32_t>(mode);
  }

  void cancel_resend() {
    if (resend_timer != 0) loop.cancel(resend_timer);
    resend_timer = 0;
    resend_setpoint.reset();
  }

  Result<void> need_guided() const {
    if (auto r = need_link(); !r) return r;
    if (tm.mode != FlightMode::kGuided) {
      return Result<void>::fail(Error::kNotReady, std::string("setpoints need GUIDED; the vehicle is in ") +
                                                      mode_name(tm.mode));
    }
    return {};
  }

  msg::SetPositionTargetLocalNed local_setpoint(std::uint16_t mask) const {
    msg::SetPositionTargetLocalNed sp;
    sp.target_system = target_sysid;
    sp.target_component = target_compid;
    sp.coordinate_frame = mav_frame(MavFrame::LocalNed);
    sp.type_mask = mask;
    sp.time_boot_ms = static_cast<std::uint32_t>(std::max(0.0, loop.now()) * 1000.0);
    return sp;
  }

  Result<void> send_setpoint(const msg::SetPositionTargetLocalNed& sp, bool resend) {
    cancel_resend();
    if (!send(sp)) return Result<void>::fail(Error::kConnectionLost, "the link was lost");
    if (resend) {
      resend_setpoint = sp;
      resend_timer = loop.call_every(config.setpoint_resend_s, [this] {
        if (resend_setpoint) send(*resend_setpoint);
      });
    }
    return {};
  }

  bool ready_now() const {
    // an armed vehicle (taken over in flight) is past its pre-arm checks
    return fd >= 0 && link_up && tm.heartbeat_seen && tm.home_set && tm.gps_fix_type >= 3 && tm.ekf_ok &&
           (tm.prearm_ok || tm.armed);
  }
};

// ---------------------------------------------------------------------------------------------------- Vehicle

Vehicle::Vehicle(EventLoop& loop, VehicleConfig config) : impl_(std::make_unique<Impl>(loop, std::move(config))) {
  loop.assert_in_loop_thread();
  impl_->target_sysid = impl_->config.target_sysid;
  Impl* self = impl_.get();
  impl_->seq_source = LoopServices(loop).add_seq_source([self]() -> std::optional<std::pair<std::string, int>> {
    if (!self->sent_any || self->fd < 0) return std::nullopt;
    std::string key = self->config.sim_vehicle;
    if (key.empty()) key = std::to_string(std::max(0, static_cast<int>(self->target_sysid) - 1));
    return std::make_pair(key, static_cast<int>(self->last_seq));
  });
  impl_->output_flusher = LoopServices(loop).add_output_flusher([self] { self->release_held(); });
}

Vehicle::~Vehicle() {
  // pending non-blocking commands end silently: their callbacks may reach this vehicle
  for (auto& [cmd, a] : impl_->async_commands) {
    if (a.retry != 0) impl_->loop.cancel(a.retry);
  }
  impl_->async_commands.clear();
  impl_->close_link(nullptr);
  LoopServices(impl_->loop).remove_seq_source(impl_->seq_source);
  LoopServices(impl_->loop).remove_output_flusher(impl_->output_flusher);
}

EventLoop& Vehicle::loop() { return impl_->loop; }

std::string Vehicle::address_from_env(const std::string& fallback) {
  const char* env = std::getenv("UAVSIM_MAVLINK");
  return env != nullptr && *env != '\0' ? std::string(env) : fallback;
}

Result<void> Vehicle::connect(const std::string& address, double timeout_s) {
  Impl& s = *impl_;
  s.loop.assert_in_loop_thread();
  s.close_link(nullptr);
  const auto where = net::parse_link_address(address);
  if (!where) {
    return Result<void>::fail(Error::kInvalidArgument, "bad vehicle address '" + address +
                                                           "' (tcp:HOST:PORT, udp:HOST:PORT or udpin:ADDR:PORT)");
  }
  s.address = address;
  const double start = s.loop.now();
  using Kind = net::LinkAddress::Kind;
  s.udp = where->kind != Kind::kTcp;
  s.udp_peer = where->kind == Kind::kUdp;
  auto fd = s.udp ? net::udp_open(where->host, where->port, where->kind == Kind::kUdpIn)
                  : net::tcp_connect(where->host, where->port, std::min(timeout_s, 30.0));
  if (!fd) return Result<void>(fd.error());
  s.fd = *fd;
  s.link_up = true;
  s.parser.reset();
  s.tm = Telemetry{};
  s.acks.clear();
  s.target_sysid = s.config.target_sysid;
  if (auto w = s.loop.watch_fd(s.fd, EventLoop::kReadable, [&s](std::uint32_t what) { s.on_io(what); }); !w) {
    s.close_link(nullptr);
    return w;
  }
  s.send_heartbeat();
  s.heartbeat_timer = s.loop.call_every(s.config.heartbeat_period_s, [&s] { s.send_heartbeat(); });
  const double left = std::max(0.0, timeout_s - (s.loop.now() - start));
  auto w = s.loop.run_until([&s] { return s.tm.heartbeat_seen || s.fd < 0; }, left, "the vehicle's heartbeat");
  if (s.fd < 0) return Result<void>::fail(Error::kConnectionLost, address + ": closed before a heartbeat arrived");
  if (!w) {
    s.close_link(nullptr);
    return Result<void>::fail(w.code(), address + ": connected, but " + w.message());
  }
  s.request_streams();
  // home is sent on request (and when it changes): ask until it is there
  s.home_timer = s.loop.call_every(1.0, [&s] {
    if (s.tm.home_set) {
      s.loop.cancel(s.home_timer);
      s.home_timer = 0;
      return;
    }
    msg::CommandLong c;
    c.target_system = s.target_sysid;
    c.target_component = s.target_compid;
    c.command = mav_command(MavCmd::RequestMessage);
    c.param1 = static_cast<float>(msg::HomePosition::kId);
    s.send(c);
  });
  return {};
}

void Vehicle::disconnect() {
  impl_->loop.assert_in_loop_thread();
  impl_->close_link(nullptr);
}

bool Vehicle::connected() const { return impl_->fd >= 0 && impl_->link_up; }
bool Vehicle::ready() const { return impl_->ready_now(); }
const Telemetry& Vehicle::telemetry() const { return impl_->tm; }
void Vehicle::on_telemetry(std::function<void(const Telemetry&)> fn) { impl_->on_telemetry = std::move(fn); }
void Vehicle::on_status_text(std::function<void(int, const std::string&)> fn) { impl_->on_status = std::move(fn); }
const std::vector<std::string>& Vehicle::status_texts() const { return impl_->texts; }

Result<void> Vehicle::wait_ready(double timeout_s) {
  Impl& s = *impl_;
  s.loop.assert_in_loop_thread();
  if (auto r = s.need_link(); !r) return r;
  auto w = s.loop.run_until([&s] { return s.ready_now() || s.fd < 0; }, timeout_s, "the vehicle to be ready");
  if (s.ready_now()) return {};
  if (s.fd < 0) return Result<void>::fail(Error::kConnectionLost, "the link was lost while waiting for the vehicle to be ready");
  if (!w && w.code() != Error::kTimeout) return w;
  std::ostringstream os;
  os << "vehicle not ready after " << timeout_s << " s:";
  if (!s.tm.home_set) os << " no home position;";
  if (s.tm.gps_fix_type < 3) os << " GPS fix type " << s.tm.gps_fix_type << ";";
  if (!s.tm.ekf_ok) os << " EKF has no horizontal position;";
  if (!s.tm.prearm_ok && !s.tm.armed) os << " pre-arm checks failing;";
  if (!s.texts.empty()) os << " last message: " << s.texts.back();
  return Result<void>::fail(Error::kTimeout, os.str());
}

Result<void> Vehicle::set_mode(FlightMode mode) {
  Impl& s = *impl_;
  if (mode != FlightMode::kGuided) s.cancel_resend();
  auto r = s.command(176, Impl::set_mode_params(mode));
  if (!r) return Result<void>::fail(r.code(), std::string("set mode ") + mode_name(mode) + ": " + r.message(), r.error().mav_result);
  s.note_mode(mode);
  return {};
}

Result<void> Vehicle::arm(bool force) {
  auto r = impl_->command(400, Impl::arm_params(force));
  if (!r) {
    std::string why = r.message();
    if (!impl_->texts.empty()) why += " (vehicle: " + impl_->texts.back() + ")";
    return Result<void>::fail(r.code(), "arm: " + why, r.error().mav_result);
  }
  impl_->tm.armed = true;
  return {};
}

Result<void> Vehicle::disarm(bool force) {
  impl_->cancel_resend();
  auto r = impl_->command(400, {0.0f, force ? 21196.0f : 0.0f, 0, 0, 0, 0, 0});
  if (!r) return Result<void>::fail(r.code(), "disarm: " + r.message(), r.error().mav_result);
  impl_->tm.armed = false;
  return {};
}

Result<void> Vehicle::takeoff(double rel_alt_m, bool wait, double timeout_s) {
  Impl& s = *impl_;
  if (!std::isfinite(rel_alt_m) || rel_alt_m <= 0) {
    return Result<void>::fail(Error::kInvalidArgument, "take-off altitude must be > 0");
  }
  s.cancel_resend();
  auto r = s.command(22, {0, 0, 0, 0, 0, 0, static_cast<float>(rel_alt_m)});
  if (!r) return Result<void>::fail(r.code(), "take-off: " + r.message(), r.error().mav_result);
  if (!wait) return {};
  return s.loop.run_until(
      [&] { return s.fd < 0 || (s.tm.has_global_position && std::abs(s.tm.relative_alt_m - rel_alt_m) < 0.5); },
      timeout_s, "take-off altitude " + std::to_string(rel_alt_m) + " m");
}

void Vehicle::command_long_async(std::uint16_t command, const std::array<float, 7>& params,
                                 std::function<void(Result<void>)> done) {
  impl_->command_async(command, params, std::move(done));
}

void Vehicle::set_mode_async(FlightMode mode, std::function<void(Result<void>)> done) {
  Impl& s = *impl_;
  if (mode != FlightMode::kGuided) s.cancel_resend();
  s.command_async(176, Impl::set_mode_params(mode), [&s, mode, done = std::move(done)](Result<void> r) {
    if (r) s.note_mode(mode);
    if (done) done(r);
  });
}

void Vehicle::arm_async(std::function<void(Result<void>)> done) {
  Impl& s = *impl_;
  s.command_async(400, Impl::arm_params(false), [&s, done = std::move(done)](Result<void> r) {
    if (r) s.tm.armed = true;
    if (done) done(r);
  });
}

void Vehicle::takeoff_async(double rel_alt_m, std::function<void(Result<void>)> done) {
  Impl& s = *impl_;
  if (!std::isfinite(rel_alt_m) || rel_alt_m <= 0) {
    auto r = Result<void>::fail(Error::kInvalidArgument, "take-off altitude must be > 0");
    if (done) s.loop.post([done = std::move(done), r] { done(r); });
    return;
  }
  s.cancel_resend();
  s.command_async(22, {0, 0, 0, 0, 0, 0, static_cast<float>(rel_alt_m)}, std::move(done));
}

void Vehicle::land_async(std::function<void(Result<void>)> done) {
  impl_->cancel_resend();
  impl_->command_async(21, {}, std::move(done));
}

Result<void> Vehicle::land(bool wait, double timeout_s) {
  Impl& s = *impl_;
  s.cancel_resend();
  auto r = s.command(21, {});
  if (!r) return Result<void>::fail(r.code(), "land: " + r.message(), r.error().mav_result);
  if (!wait) return {};
  auto w = s.loop.run_until([&] { return s.fd < 0 || (s.tm.mode == FlightMode::kLand && !s.tm.armed); }, timeout_s,
                            "landing and disarm");
  if (s.fd < 0) return Result<void>::fail(Error::kConnectionLost, "land: the link was lost");
  return w;
}

Result<void> Vehicle::return_to_launch() {
  impl_->cancel_resend();
  auto r = impl_->command(20, {});
  if (!r) return Result<void>::fail(r.code(), "RTL: " + r.message(), r.error().mav_result);
  impl_->tm.mode = FlightMode::kRtl;
  return {};
}

Result<void> Vehicle::goto_local_ned(const Eigen::Vector3d& ned_m, double yaw_ned_rad) {
  Impl& s = *impl_;
  s.loop.assert_in_loop_thread();
  if (!ned_m.allFinite()) return Result<void>::fail(Error::kInvalidArgument, "goto: position must be finite");
  if (auto r = s.need_guided(); !r) return r;
  auto sp = s.local_setpoint(std::isfinite(yaw_ned_rad) ? kMaskPosYaw : kMaskPos);
  sp.x = static_cast<float>(ned_m.x());
  sp.y = static_cast<float>(ned_m.y());
  sp.z = static_cast<float>(ned_m.z());
  if (std::isfinite(yaw_ned_rad)) sp.yaw = static_cast<float>(yaw_ned_rad);
  return s.send_setpoint(sp, false);
}

Result<void> Vehicle::goto_local_enu(const Eigen::Vector3d& enu_m, double yaw_enu_rad) {
  return goto_local_ned(ned_from_enu(enu_m), std::isfinite(yaw_enu_rad) ? ned_yaw_from_enu(yaw_enu_rad) : kNaN);
}

Result<void> Vehicle::goto_geodetic(const Geodetic& p, double yaw_ned_rad) {
  Impl& s = *impl_;
  s.loop.assert_in_loop_thread();
  if (!std::isfinite(p.lat_deg) || !std::isfinite(p.lon_deg) || !std::isfinite(p.alt_m) || std::abs(p.lat_deg) > 90 ||
      std::abs(p.lon_deg) > 180) {
    return Result<void>::fail(Error::kInvalidArgument, "goto: invalid latitude/longitude/altitude");
  }
  if (auto r = s.need_guided(); !r) return r;
  s.cancel_resend();
  msg::SetPositionTargetGlobalInt sp;
  sp.target_system = s.target_sysid;
  sp.target_component = s.target_compid;
  sp.coordinate_frame = mav_frame(MavFrame::GlobalInt);  // altitude AMSL
  sp.type_mask = std::isfinite(yaw_ned_rad) ? kMaskPosYaw : kMaskPos;
  sp.lat_int = e7(p.lat_deg);
  sp.lon_int = e7(p.lon_deg);
  sp.alt = static_cast<float>(p.alt_m);
  if (std::isfinite(yaw_ned_rad)) sp.yaw = static_cast<float>(yaw_ned_rad);
  sp.time_boot_ms = static_cast<std::uint32_t>(std::max(0.0, s.loop.now()) * 1000.0);
  if (!s.send(sp)) return Result<void>::fail(Error::kConnectionLost, "the link was lost");
  return {};
}

Result<void> Vehicle::wait_position_enu(const Eigen::Vector3d& enu_m, double tolerance_m, double timeout_s) {
  Impl& s = *impl_;
  std::ostringstream what;
  what << "position (" << enu_m.x() << ", " << enu_m.y() << ", " << enu_m.z() << ") ENU within " << tolerance_m << " m";
  auto w = s.loop.run_until(
      [&] { return s.fd < 0 || (s.tm.has_local_position && (s.tm.position_enu_m - enu_m).norm() < tolerance_m); },
      timeout_s, what.str());
  if (s.fd < 0) return Result<void>::fail(Error::kConnectionLost, "the link was lost waiting for " + what.str());
  return w;
}

Result<void> Vehicle::set_velocity_enu(const Eigen::Vector3d& v, double yaw_rate_enu_rad_s) {
  Impl& s = *impl_;
  s.loop.assert_in_loop_thread();
  if (!v.allFinite() || v.norm() > 100.0) return Result<void>::fail(Error::kInvalidArgument, "velocity must be finite and < 100 m/s");
  if (auto r = s.need_guided(); !r) return r;
  const bool rate = std::isfinite(yaw_rate_enu_rad_s);
  auto sp = s.local_setpoint(rate ? kMaskVelYawRate : kMaskVel);
  const Eigen::Vector3d ned = ned_from_enu(v);
  sp.vx = static_cast<float>(ned.x());
  sp.vy = static_cast<float>(ned.y());
  sp.vz = static_cast<float>(ned.z());
  if (rate) sp.yaw_rate = static_cast<float>(-yaw_rate_enu_rad_s);  // NED yaw rate is clockwise
  return s.send_setpoint(sp, true);
}

Result<void> Vehicle::set_velocity_enu_yaw(const Eigen::Vector3d& v, double yaw_enu_rad) {
  Impl& s = *impl_;
  s.loop.assert_in_loop_thread();
  if (!v.allFinite() || !std::isfinite(yaw_enu_rad)) return Result<void>::fail(Error::kInvalidArgument, "velocity and yaw must be finite");
  if (auto r = s.need_guided(); !r) return r;
  auto sp = s.local_setpoint(kMaskVelYaw);
  const Eigen::Vector3d ned = ned_from_enu(v);
  sp.vx = static_cast<float>(ned.x());
  sp.vy = static_cast<float>(ned.y());
  sp.vz = static_cast<float>(ned.z());
  sp.yaw = static_cast<float>(ned_yaw_from_enu(yaw_enu_rad));
  return s.send_setpoint(sp, true);
}

Result<void> Vehicle::stop() {
  Impl& s = *impl_;
  s.loop.assert_in_loop_thread();
  s.cancel_resend();
  if (auto r = s.need_guided(); !r) return r;
  // hold here: position target at the current position
  auto sp = s.local_setpoint(kMaskPos);
  sp.x = static_cast<float>(s.tm.position_ned_m.x());
  sp.y = static_cast<float>(s.tm.position_ned_m.y());
  sp.z = static_cast<float>(s.tm.position_ned_m.z());
  return s.send_setpoint(sp, false);
}

Result<void> Vehicle::set_yaw(double heading_deg, double rate_deg_s, bool relative) {
  if (!std::isfinite(heading_deg) || !std::isfinite(rate_deg_s)) return Result<void>::fail(Error::kInvalidArgument, "yaw must be finite");
  float angle = static_cast<float>(heading_deg);
  float dir = 0.0f;
  if (relative) {
    dir = heading_deg < 0 ? -1.0f : 1.0f;
    angle = static_cast<float>(std::abs(heading_deg));
  } else {
    angle = static_cast<float>(std::fmod(std::fmod(heading_deg, 360.0) + 360.0, 360.0));
  }
  auto r = impl_->command(115, {angle, static_cast<float>(rate_deg_s), dir, relative ? 1.0f : 0.0f, 0, 0, 0});
  if (!r) return Result<void>::fail(r.code(), "yaw: " + r.message(), r.error().mav_result);
  return {};
}

Result<void> Vehicle::point_gimbal(double pitch_deg, double yaw_deg, double roll_deg) {
  if (!std::isfinite(pitch_deg) || !std::isfinite(yaw_deg) || !std::isfinite(roll_deg)) {
    return Result<void>::fail(Error::kInvalidArgument, "gimbal angles must be finite");
  }
  // DO_MOUNT_CONTROL: pitch, roll, yaw (deg), mode MAV_MOUNT_MODE_MAVLINK_TARGETING (2) in param7
  auto r = impl_->command(205, {static_cast<float>(pitch_deg), static_cast<float>(roll_deg), static_cast<float>(yaw_deg),
                                0, 0, 0, 2.0f});
  if (!r) return Result<void>::fail(r.code(), "gimbal: " + r.message(), r.error().mav_result);
  return {};
}

Result<void> Vehicle::command_long(std::uint16_t command, const std::array<float, 7>& params) {
  return impl_->command(command, params);
}

Result<void> Vehicle::upload_mission(const std::vector<MissionItem>& items, double timeout_s) {
  Impl& s = *impl_;
  s.loop.assert_in_loop_thread();
  if (auto r = s.need_link(); !r) return r;
  if (items.empty()) return Result<void>::fail(Error::kInvalidArgument, "an empty mission");
  s.mission.clear();
  auto to_wire = [&](const MissionItem& it, std::uint16_t seq) {
    msg::MissionItemInt m;
    m.target_system = s.target_sysid;
    m.target_component = s.target_compid;
    m.seq = seq;
    m.frame = it.frame;
    m.command = it.command;
    m.autocontinue = it.autocontinue ? 1 : 0;
    m.param1 = it.param1, m.param2 = it.param2, m.param3 = it.param3, m.param4 = it.param4;
    m.x = e7(it.lat_deg);
    m.y = e7(it.lon_deg);
    m.z = it.alt_m;
    m.mission_type = kMissionTypeMission;
    return m;
  };
  MissionItem home;  // item 0: home (ArduPilot overwrites it with the real home)
  home.frame = mav_frame(MavFrame::Global);
  home.lat_deg = s.tm.home.lat_deg;
  home.lon_deg = s.tm.home.lon_deg;
  home.alt_m = static_cast<float>(s.tm.home.alt_m);
  s.mission.push_back(to_wire(home, 0));
  for (std::size_t i = 0; i < items.size(); ++i) s.mission.push_back(to_wire(items[i], static_cast<std::uint16_t>(i + 1)));
  s.mission_active = true;
  s.mission_ack.reset();
  s.mission_requests = 0;

  const double deadline = s.loop.now() + timeout_s;
  Result<void> outcome = Result<void>::fail(Error::kTimeout, "mission upload: no MISSION_ACK within " + std::to_string(timeout_s) + " s");
  for (int attempt = 0; attempt < 3 && s.loop.now() < deadline; ++attempt) {
    msg::MissionCount c;
    c.target_system = s.target_sysid;
    c.target_component = s.target_compid;
    c.count = static_cast<std::uint16_t>(s.mission.size());
    c.mission_type = kMissionTypeMission;
    if (!s.send(c)) break;
    const double sent_at = s.loop.now();
    (void)s.loop.run_until(
        [&] {
          return s.mission_ack.has_value() || s.fd < 0 || (s.mission_requests == 0 && s.loop.now() - sent_at > 1.5);
        },
        std::max(0.0, deadline - s.loop.now()), "MISSION_ACK");
    if (s.mission_ack || s.fd < 0 || s.mission_requests > 0) break;
  }
  if (s.fd < 0) {
    outcome = Result<void>::fail(Error::kConnectionLost, "mission upload: the link was lost");
  } else if (s.mission_ack) {
    const int r = *s.mission_ack;
    outcome = r == 0 ? Result<void>()
                     : Result<void>::fail(r == 15 ? Error::kCancelled : Error::kDenied,
                                          std::string("mission upload refused: MAV_MISSION_") + mission_result_name(r) +
                                              " (" + std::to_string(r) + ")",
                                          r);
  } else if (s.mission_requests == 0) {
    outcome = Result<void>::fail(Error::kTimeout, "mission upload: the vehicle never requested an item");
  }
  s.mission_active = false;
  return outcome;
}

Result<void> Vehicle::start_mission() {
  impl_->cancel_resend();
  auto r = impl_->command(300, {0, 0, 0, 0, 0, 0, 0});
  if (!r) return Result<void>::fail(r.code(), "mission start: " + r.message(), r.error().mav_result);
  impl_->tm.mode = FlightMode::kAuto;
  return {};
}

Result<float> Vehicle::get_param(const std::string& name, double timeout_s) {
  Impl& s = *impl_;
  s.loop.assert_in_loop_thread();
  if (auto r = s.need_link(); !r) return Result<float>(r.error());
  if (name.empty() || name.size() > 16) return Result<float>::fail(Error::kInvalidArgument, "parameter names have 1-16 characters");
  const std::uint64_t before = s.params[name].count;
  const double deadline = s.loop.now() + timeout_s;
  while (s.loop.now() < deadline && s.fd >= 0) {
    msg::ParamRequestRead rq;
    rq.target_system = s.target_sysid;
    rq.target_component = s.target_compid;
    rq.param_index = -1;
    mav::set_string(rq.param_id, name);
    s.send(rq);
    (void)s.loop.run_until([&] { return s.params[name].count > before || s.fd < 0; },
                           std::min(1.0, deadline - s.loop.now()), "PARAM_VALUE");
    if (s.params[name].count > before) return s.params[name].value;
  }
  if (s.fd < 0) return Result<float>::fail(Error::kConnectionLost, "get " + name + ": the link was lost");
  return Result<float>::fail(Error::kTimeout, "no PARAM_VALUE for " + name + " within " + std::to_string(timeout_s) +
                                                  " s (unknown parameter?)");
}

Result<float> Vehicle::set_param(const std::string& name, float value, double timeout_s) {
  Impl& s = *impl_;
  s.loop.assert_in_loop_thread();
  if (auto r = s.need_link(); !r) return Result<float>(r.error());
  if (name.empty() || name.size() > 16) return Result<float>::fail(Error::kInvalidArgument, "parameter names have 1-16 characters");
  if (!std::isfinite(value)) return Result<float>::fail(Error::kInvalidArgument, "parameter values must be finite");
  const std::uint64_t before = s.params[name].count;
  const std::uint8_t type =
      s.params[name].count > 0 ? s.params[name].type : to_underlying(mav::MavParamType::Real32);
  const double deadline = s.loop.now() + timeout_s;
  while (s.loop.now() < deadline && s.fd >= 0) {
    msg::ParamSet ps;
    ps.target_system = s.target_sysid;
    ps.target_component = s.target_compid;
    mav::set_string(ps.param_id, name);
    ps.param_value = value;
    ps.param_type = type;
    s.send(ps);
    (void)s.loop.run_until([&] { return s.params[name].count > before || s.fd < 0; },
                           std::min(1.0, deadline - s.loop.now()), "PARAM_VALUE");
    if (s.params[name].count > before) {
      const float got = s.params[name].value;
      if (std::abs(got - value) > 1e-6f * std::max(1.0f, std::abs(value))) {
        std::ostringstream os;
        os << "set " << name << " = " << value << ": the vehicle kept " << got;
        return Result<float>::fail(Error::kDenied, os.str());
      }
      return got;
    }
  }
  if (s.fd < 0) return Result<float>::fail(Error::kConnectionLost, "set " + name + ": the link was lost");
  return Result<float>::fail(Error::kTimeout, "no PARAM_VALUE echo for " + name + " within " + std::to_string(timeout_s) +
                                                  " s (unknown parameter?)");
}

}  // namespace uavsim::client
