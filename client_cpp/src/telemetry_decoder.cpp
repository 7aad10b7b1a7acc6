// Telemetry decoding: each message the vehicle streams updates its part of the cache. Units and
// flags as ArduCopter sends them (docs/mavlink.md).
#include "telemetry_decoder.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <utility>

#include "mav_units.hpp"
#include "uavsim/common/frames.hpp"
#include "uavsim/common/mavlink/generated/enums.hpp"
#include "uavsim/common/mavlink/wire.hpp"

namespace uavsim::client {

namespace mav = common::mavlink;
namespace msg = common::mavlink::msg;
using mav::to_underlying;

namespace {

constexpr std::size_t kKeptStatusTexts = 100;
constexpr std::uint16_t kHeadingUnknown = 65535;  // GLOBAL_POSITION_INT.hdg: UINT16_MAX if unknown
constexpr double kHomeRequestPeriodS = 1.0;
// the stream groups' rates: position and attitude at the configured rate, status slower
constexpr std::uint16_t kStatusStreamHz = 2;
constexpr std::uint16_t kExtra2StreamHz = 4;  // VFR_HUD
constexpr std::uint16_t kExtra3StreamHz = 2;  // battery, EKF status
constexpr long kMaxStreamHz = 50;

constexpr std::uint32_t bit(mav::MavSysStatusSensor s) { return to_underlying(s); }
constexpr std::uint16_t bit(mav::EkfStatusFlags f) {
  return static_cast<std::uint16_t>(to_underlying(f));
}

}  // namespace

template <class Msg>
void TelemetryDecoder::route(void (TelemetryDecoder::*apply)(const Msg&)) {
  port_.on_message(Msg::kId, [this, apply](const mav::Frame& f) {
    (this->*apply)(Msg::decode(f.payload.data()));
    if (changed_) changed_();
  });
}

TelemetryDecoder::TelemetryDecoder(EventLoop& loop, MavPort& port) : loop_(loop), port_(port) {
  route<msg::Heartbeat>(&TelemetryDecoder::apply);
  route<msg::SysStatus>(&TelemetryDecoder::apply);
  route<msg::GpsRawInt>(&TelemetryDecoder::apply);
  route<msg::LocalPositionNed>(&TelemetryDecoder::apply);
  route<msg::GlobalPositionInt>(&TelemetryDecoder::apply);
  route<msg::Attitude>(&TelemetryDecoder::apply);
  route<msg::BatteryStatus>(&TelemetryDecoder::apply);
  route<msg::ExtendedSysState>(&TelemetryDecoder::apply);
  route<msg::EkfStatusReport>(&TelemetryDecoder::apply);
  route<msg::HomePosition>(&TelemetryDecoder::apply);
  route<msg::GpsGlobalOrigin>(&TelemetryDecoder::apply);
  route<msg::MountStatus>(&TelemetryDecoder::apply);
  route<msg::GimbalDeviceAttitudeStatus>(&TelemetryDecoder::apply);
  route<msg::MissionCurrent>(&TelemetryDecoder::apply);
  route<msg::MissionItemReached>(&TelemetryDecoder::apply);
  port_.on_message(msg::Statustext::kId, [this](const mav::Frame& f) {
    add_status_text(msg::Statustext::decode(f.payload.data()));
  });
}

TelemetryDecoder::~TelemetryDecoder() { stop(); }

void TelemetryDecoder::request_streams(double rate_hz) {
  const auto rate = static_cast<std::uint16_t>(std::clamp(std::lround(rate_hz), 1L, kMaxStreamHz));
  using Stream = mav::MavDataStream;
  const std::pair<Stream, std::uint16_t> groups[] = {{Stream::ExtendedStatus, kStatusStreamHz},
                                                     {Stream::Position, rate},
                                                     {Stream::Extra1, rate},
                                                     {Stream::Extra2, kExtra2StreamHz},
                                                     {Stream::Extra3, kExtra3StreamHz}};
  for (const auto& [id, hz] : groups) {
    msg::RequestDataStream r;
    r.target_system = port_.target_sysid();
    r.target_component = port_.target_compid();
    r.req_stream_id = static_cast<std::uint8_t>(to_underlying(id));
    r.req_message_rate = hz;
    r.start_stop = 1;  // start
    port_.send(r);
  }
  // not in any stream group: ask for them by interval (acks are not awaited)
  const std::pair<std::uint32_t, double> intervals[] = {{msg::HomePosition::kId, 1.0},
                                                        {msg::ExtendedSysState::kId, 1.0},
                                                        {msg::GpsGlobalOrigin::kId, 5.0},
                                                        {msg::MountStatus::kId, 0.5}};
  for (const auto& [id, period] : intervals) {
    msg::CommandLong c;
    c.target_system = port_.target_sysid();
    c.target_component = port_.target_compid();
    c.command = to_underlying(mav::MavCmd::SetMessageInterval);
    c.param1 = static_cast<float>(id);
    c.param2 = static_cast<float>(period * 1e6);  // microseconds
    port_.send(c);
  }
  // home is sent on request (and when it changes): ask until it is there
  stop();
  home_timer_ = loop_.call_every(kHomeRequestPeriodS, [this] {
    if (tm_.home_set) {
      stop();
      return;
    }
    msg::CommandLong c;
    c.target_system = port_.target_sysid();
    c.target_component = port_.target_compid();
    c.command = to_underlying(mav::MavCmd::RequestMessage);
    c.param1 = static_cast<float>(msg::HomePosition::kId);
    port_.send(c);
  });
}

void TelemetryDecoder::stop() {
  if (home_timer_ != 0) loop_.cancel(home_timer_);
  home_timer_ = 0;
}

void TelemetryDecoder::apply(const msg::Heartbeat& m) {
  tm_.sysid = port_.target_sysid();  // the link passes on the heartbeats of its vehicle only
  tm_.heartbeat_seen = true;
  tm_.last_heartbeat_time = loop_.now();
  tm_.custom_mode = m.custom_mode;
  tm_.mode = static_cast<FlightMode>(m.custom_mode);
  tm_.armed = (m.base_mode & to_underlying(mav::MavModeFlag::SafetyArmed)) != 0;
  tm_.system_status = m.system_status;
}

void TelemetryDecoder::apply(const msg::SysStatus& m) {
  tm_.sensors_health = m.onboard_control_sensors_health;
  tm_.prearm_ok =
      (m.onboard_control_sensors_health & bit(mav::MavSysStatusSensor::PrearmCheck)) != 0;
  tm_.battery_voltage_v = m.voltage_battery / 1000.0;  // mV
  tm_.battery_current_a = m.current_battery / 100.0;   // cA
  tm_.battery_remaining_pct = m.battery_remaining;
}

void TelemetryDecoder::apply(const msg::GpsRawInt& m) {
  tm_.gps_fix_type = m.fix_type;
  tm_.gps_satellites = m.satellites_visible;
  tm_.gps_hdop = m.eph / 100.0;  // cm
  tm_.gps_position = {deg_from_e7(m.lat), deg_from_e7(m.lon), m_from_mm(m.alt)};
}

void TelemetryDecoder::apply(const msg::LocalPositionNed& m) {
  tm_.vehicle_time_s = m.time_boot_ms / 1000.0;
  tm_.has_local_position = true;
  tm_.position_ned_m = {m.x, m.y, m.z};
  tm_.velocity_ned_m_s = {m.vx, m.vy, m.vz};
  tm_.position_enu_m = enu_from_ned(tm_.position_ned_m);
  tm_.velocity_enu_m_s = enu_from_ned(tm_.velocity_ned_m_s);
}

void TelemetryDecoder::apply(const msg::GlobalPositionInt& m) {
  tm_.has_global_position = true;
  tm_.position = {deg_from_e7(m.lat), deg_from_e7(m.lon), m_from_mm(m.alt)};
  tm_.relative_alt_m = m_from_mm(m.relative_alt);
  if (m.hdg != kHeadingUnknown) tm_.heading_deg = m.hdg / 100.0;  // cdeg
}

void TelemetryDecoder::apply(const msg::Attitude& m) {
  tm_.has_attitude = true;
  tm_.roll_rad = m.roll;
  tm_.pitch_rad = m.pitch;
  tm_.yaw_rad = m.yaw;
  tm_.body_rates_rad_s = {m.rollspeed, m.pitchspeed, m.yawspeed};
}

void TelemetryDecoder::apply(const msg::BatteryStatus& m) {
  if (m.current_consumed >= 0) tm_.battery_consumed_mah = m.current_consumed;  // -1: unknown
}

void TelemetryDecoder::apply(const msg::ExtendedSysState& m) {
  // LandedState has MAV_LANDED_STATE's numbers
  tm_.landed = static_cast<LandedState>(m.landed_state);
}

void TelemetryDecoder::apply(const msg::EkfStatusReport& m) {
  tm_.ekf_flags = m.flags;
  tm_.ekf_ok = (m.flags & bit(mav::EkfStatusFlags::PredPosHorizAbs)) != 0 ||
               (m.flags & bit(mav::EkfStatusFlags::PosHorizAbs)) != 0;
}

void TelemetryDecoder::apply(const msg::HomePosition& m) {
  tm_.home_set = true;
  tm_.home = {deg_from_e7(m.latitude), deg_from_e7(m.longitude), m_from_mm(m.altitude)};
  tm_.home_ned_m = {m.x, m.y, m.z};
}

void TelemetryDecoder::apply(const msg::GpsGlobalOrigin& m) {
  tm_.origin_set = true;
  tm_.origin = {deg_from_e7(m.latitude), deg_from_e7(m.longitude), m_from_mm(m.altitude), 0.0};
}

void TelemetryDecoder::apply(const msg::MountStatus& m) {
  tm_.has_gimbal = true;
  tm_.gimbal_pitch_deg = m.pointing_a / 100.0;  // cdeg
  tm_.gimbal_roll_deg = m.pointing_b / 100.0;
  tm_.gimbal_yaw_deg = m.pointing_c / 100.0;
}

void TelemetryDecoder::apply(const msg::GimbalDeviceAttitudeStatus& m) {
  using Flags = mav::GimbalDeviceFlags;
  Eigen::Quaterniond q(m.q[0], m.q[1], m.q[2], m.q[3]);
  if (!(q.norm() > 0.5)) return;  // NaN or no attitude
  // earth frame: the YAW_IN_EARTH_FRAME flag, or (older devices, neither frame flag) a yaw lock
  const bool in_vehicle_frame = (m.flags & to_underlying(Flags::YawInVehicleFrame)) != 0;
  const bool in_earth_frame = (m.flags & to_underlying(Flags::YawInEarthFrame)) != 0 ||
                              (!in_vehicle_frame && (m.flags & to_underlying(Flags::YawLock)) != 0);
  if (in_earth_frame) {
    if (!std::isfinite(m.delta_yaw)) return;  // no way back to the vehicle frame
    q = Eigen::AngleAxisd(-m.delta_yaw, Eigen::Vector3d::UnitZ()) *
        q;  // q_earth = q_delta_yaw * q_vehicle
  }
  const common::frames::Euler e = common::frames::euler_from_q_ned_frd(q.normalized());
  tm_.has_gimbal_attitude = true;
  tm_.gimbal_attitude_time_s = m.time_boot_ms / 1000.0;
  tm_.gimbal_attitude_roll_rad = e.roll_rad;
  tm_.gimbal_attitude_pitch_rad = e.pitch_rad;
  tm_.gimbal_attitude_yaw_rad = e.yaw_rad;
}

void TelemetryDecoder::apply(const msg::MissionCurrent& m) { tm_.mission_current = m.seq; }

void TelemetryDecoder::apply(const msg::MissionItemReached& m) { tm_.mission_last_reached = m.seq; }

void TelemetryDecoder::add_status_text(const msg::Statustext& m) {
  std::string text(mav::get_string(m.text));
  texts_.push_back(text);
  if (texts_.size() > kKeptStatusTexts) texts_.erase(texts_.begin());
  if (status_) status_(m.severity, text);
}

}  // namespace uavsim::client
