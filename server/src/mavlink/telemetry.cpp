// Telemetry: the messages the vehicle streams (when, per client: telemetry_schedule.hpp) and sends
// on request. Every time_boot_ms / time_usec is simulation time since start, as in SITL
// (docs/mavlink.md §8), and every value comes from the flight controller's estimate, never from
// ground truth, but for the gimbal's attitude: its device's (EndpointConfig::gimbal_attitude).
//
// Stream groups follow ArduCopter's REQUEST_DATA_STREAM groups (docs/mavlink.md §9). Default rates
// per client: EXTENDED_STATUS 2 Hz, POSITION 4 Hz, EXTRA1 4 Hz, EXTRA2 4 Hz, EXTRA3 2 Hz, HEARTBEAT
// 1 Hz. ArduPilot sets its rates per serial port (SRn_ parameters); these are about what a
// MAVProxy-driven SITL link carries (MAVProxy asks for the groups on connect), so a client that
// never asks still sees every vehicle message.
#include <algorithm>
#include <cmath>
#include <limits>

#include "airframe/airframe.hpp"
#include "mavlink/vehicle_link.hpp"
#include "uavsim/common/angles.hpp"
#include "uavsim/common/frames.hpp"

namespace uavsim::server::mavlink {

namespace frames = ::uavsim::common::frames;

namespace {

using common::kRadToDeg;

// an enumerator (or an or of bitmask enumerators) as a message field of type T holds it
template <class T, class E>
constexpr T field(std::initializer_list<E> values) {
  std::uint64_t v = 0;
  for (E e : values) v |= static_cast<std::uint64_t>(to_underlying(e));
  return static_cast<T>(v);
}
template <class T, class E>
constexpr T field(E value) {
  return field<T>({value});
}
// SYSTEM_TIME.time_unix_usec: a fixed epoch (2024-01-01 00:00:00 UTC) plus sim time, so runs are reproducible
constexpr std::uint64_t kSimEpochUnixUs = 1704067200ULL * 1000000ULL;

std::int32_t deg_e7(double deg) { return static_cast<std::int32_t>(std::llround(deg * 1e7)); }

template <class T>
T clamp_to(double v) {
  const double lo = static_cast<double>(std::numeric_limits<T>::lowest());
  const double hi = static_cast<double>(std::numeric_limits<T>::max());
  if (!std::isfinite(v)) return 0;
  return static_cast<T>(std::llround(std::clamp(v, lo, hi)));
}

using common::kDegToRad;

double wrap_180(double deg) { return std::remainder(deg, 360.0); }

// The attitude of a gimbal that follows its command at once: roll and pitch as commanded (relative
// to the horizon), yaw relative to the heading (a commanded heading less the vehicle's)
GimbalDeviceAttitude commanded_attitude(const GimbalState& g, double vehicle_yaw_deg) {
  return {g.roll_deg, g.pitch_deg,
          wrap_180(g.yaw_earth_frame ? g.yaw_deg - vehicle_yaw_deg : g.yaw_deg)};
}

std::uint8_t landed_state_number(fc::LandedState s) {
  switch (s) {
    case fc::LandedState::kOnGround: return field<std::uint8_t>(MavLandedState::OnGround);
    case fc::LandedState::kInAir: return field<std::uint8_t>(MavLandedState::InAir);
    case fc::LandedState::kTakeoff: return field<std::uint8_t>(MavLandedState::Takeoff);
    case fc::LandedState::kLanding: return field<std::uint8_t>(MavLandedState::Landing);
  }
  return field<std::uint8_t>(MavLandedState::Undefined);
}

}  // namespace

std::uint64_t VehicleLink::signing_now_10us() const {
  const double elapsed_s = std::max(0.0, now_s() - signing_set_s_);
  const std::uint64_t advanced = signing_initial_10us_ + static_cast<std::uint64_t>(std::llround(elapsed_s * 1e5));
  const std::uint64_t gps =
      signing_timestamp_from_unix_us(kSimEpochUnixUs + static_cast<std::uint64_t>(std::llround(now_s() * 1e6)));
  return std::max(advanced, gps);
}

bool VehicleLink::can_send(std::uint32_t msgid) const {
  return msgid == msg::AutopilotVersion::kId || TelemetrySchedule::streamable(msgid);
}

void VehicleLink::handle_request_data_stream(Link& link, const msg::RequestDataStream& m) {
  // stream 0 (ALL) sets every group; start_stop 0 or rate 0 stops
  link.streams.set_group_rate(m.req_stream_id, m.req_message_rate, m.start_stop != 0, now_s());
}

void VehicleLink::handle_timesync(Link& link, const msg::Timesync& m) {
  if (m.tc1 != 0) return;  // a reply to our own request: nothing to estimate here
  msg::Timesync r;
  r.tc1 = static_cast<std::int64_t>(std::llround(now_s() * 1e9));
  r.ts1 = m.ts1;
  send(link, r);
}

Geodetic VehicleLink::geodetic_of_enu(const Eigen::Vector3d& p_enu) const {
  return common::geodetic_from_enu(config_.origin, p_enu);
}

Eigen::Vector3d VehicleLink::enu_of_geodetic(const Geodetic& g) const {
  return common::enu_from_geodetic(config_.origin, g);
}

msg::Heartbeat VehicleLink::heartbeat() const {
  const fc::FlightController& fc = sim_.fc(vehicle_);
  const fc::Mode mode = fc.mode();
  msg::Heartbeat h;
  h.type = mav_type_;
  h.autopilot = field<std::uint8_t>(MavAutopilot::Ardupilotmega);
  // CUSTOM_MODE_ENABLED | STABILIZE_ENABLED | MANUAL_INPUT_ENABLED always; GUIDED_ENABLED when the
  // horizontal position controller runs; SAFETY_ARMED when armed (docs/mavlink.md §1)
  h.base_mode = field<std::uint8_t>(
      {MavModeFlag::CustomModeEnabled, MavModeFlag::StabilizeEnabled, MavModeFlag::ManualInputEnabled});
  const bool ne_control = mode == fc::Mode::kGuided || mode == fc::Mode::kAuto || mode == fc::Mode::kLoiter ||
                          mode == fc::Mode::kRtl || mode == fc::Mode::kLand || mode == fc::Mode::kBrake;
  if (fc.armed()) h.base_mode |= field<std::uint8_t>(MavModeFlag::SafetyArmed);
  if (fc.armed() && ne_control) h.base_mode |= field<std::uint8_t>(MavModeFlag::GuidedEnabled);
  h.custom_mode = static_cast<std::uint32_t>(mode);
  if (sim_.runtime(vehicle_).crashed) {
    h.system_status = field<std::uint8_t>(MavState::Critical);
  } else if (fc.landed_state() == fc::LandedState::kOnGround) {
    h.system_status = field<std::uint8_t>(MavState::Standby);
  } else {
    h.system_status = field<std::uint8_t>(MavState::Active);
  }
  h.mavlink_version = 3;
  return h;
}

void VehicleLink::send_heartbeat(Link& link) { send(link, heartbeat()); }

void VehicleLink::send_home(Link& link) {
  const fc::FlightController& fc = sim_.fc(vehicle_);
  if (!fc.home_set()) return;
  const Eigen::Vector3d home = fc.home_enu_m();
  const Geodetic g = geodetic_of_enu(home);
  const Eigen::Vector3d ned = frames::ned_from_enu(home);
  msg::HomePosition h;
  h.latitude = deg_e7(g.lat_deg);
  h.longitude = deg_e7(g.lon_deg);
  h.altitude = clamp_to<std::int32_t>(g.alt_m * 1000.0);
  h.x = static_cast<float>(ned.x());
  h.y = static_cast<float>(ned.y());
  h.z = static_cast<float>(ned.z());
  h.q = {1.0f, 0.0f, 0.0f, 0.0f};
  h.time_usec = static_cast<std::uint64_t>(std::llround(now_s() * 1e6));
  send(link, h);
}

void VehicleLink::send_autopilot_version(Link& link) {
  msg::AutopilotVersion v;
  // MISSION_FLOAT | PARAM_FLOAT | MISSION_INT | COMMAND_INT | SET_ATTITUDE_TARGET |
  // SET_POSITION_TARGET_LOCAL_NED | SET_POSITION_TARGET_GLOBAL_INT | MAVLINK2
  v.capabilities = 1 | 2 | 4 | 8 | 64 | 128 | 256 | 8192;
  v.flight_sw_version = (4u << 24) | (5u << 16) | (0u << 8) | 255u;  // "4.5.0 official", ArduPilot's layout
  v.uid = sysid_;
  const char kCustom[8] = {'u', 'a', 'v', 's', 'i', 'm', 0, 0};
  std::copy(std::begin(kCustom), std::end(kCustom), v.flight_custom_version.begin());
  send(link, v);
}

void VehicleLink::send_status_text(int severity, std::string_view text) {
  // up to 50 characters per frame; longer texts go out in chunks sharing a non-zero id
  const bool chunked = text.size() > 50;
  const std::uint16_t id = chunked ? next_text_id_++ : 0;
  if (next_text_id_ == 0) next_text_id_ = 1;
  std::uint8_t chunk = 0;
  do {
    msg::Statustext s;
    s.severity = static_cast<std::uint8_t>(std::clamp(severity, 0, 7));
    set_string(s.text, text.substr(0, 50));
    s.id = id;
    s.chunk_seq = chunk++;
    broadcast(s);
    text = text.size() > 50 ? text.substr(50) : std::string_view{};
  } while (!text.empty());
}

bool VehicleLink::send_message_by_id(Link& link, std::uint32_t msgid) {
  const fc::FlightController& fc = sim_.fc(vehicle_);
  const fc::EstimatedState& est = fc.estimate();
  const std::uint32_t t_ms = time_boot_ms();
  switch (msgid) {
    case msg::Heartbeat::kId:
      send_heartbeat(link);
      return true;
    case msg::SysStatus::kId: {
      // gyro, accel, mag, baro, GPS, rate/attitude/yaw/z/xy control, motor outputs, AHRS, battery, pre-arm
      constexpr std::uint32_t kPresent = 1 | 2 | 4 | 8 | 32 | 1024 | 2048 | 4096 | 8192 | 16384 | 32768 |
                                         2097152 | 33554432 | 268435456;
      msg::SysStatus s;
      s.onboard_control_sensors_present = kPresent;
      s.onboard_control_sensors_enabled = kPresent;
      std::uint32_t health = kPresent;
      if (!est.gps_ok) health &= ~32u;
      if (!fc.prearm_ok()) health &= ~268435456u;
      if (sim_.runtime(vehicle_).crashed) health &= ~(32768u | 1024u | 2048u);
      s.onboard_control_sensors_health = health;
      s.load = 100;  // 10 %
      const airframe::BatteryState& b = sim_.runtime(vehicle_).battery;
      s.voltage_battery = clamp_to<std::uint16_t>(b.voltage_v * 1000.0);
      s.current_battery = clamp_to<std::int16_t>(b.current_a * 100.0);
      s.battery_remaining = clamp_to<std::int8_t>(
          100.0 * airframe::battery_remaining(sim_.airframe(vehicle_), b));
      send(link, s);
      return true;
    }
    case msg::SystemTime::kId: {
      msg::SystemTime s;
      s.time_boot_ms = t_ms;
      s.time_unix_usec = kSimEpochUnixUs + static_cast<std::uint64_t>(std::llround(now_s() * 1e6));
      send(link, s);
      return true;
    }
    case msg::GpsRawInt::kId: {
      const Geodetic g = geodetic_of_enu(est.position_enu_m);
      const Eigen::Vector3d v = frames::ned_from_enu(est.velocity_enu_m_s);
      msg::GpsRawInt m;
      m.time_usec = static_cast<std::uint64_t>(std::llround(now_s() * 1e6));
      m.fix_type = est.gps_ok ? 3 : 1;
      m.lat = deg_e7(g.lat_deg);
      m.lon = deg_e7(g.lon_deg);
      m.alt = clamp_to<std::int32_t>(g.alt_m * 1000.0);
      m.eph = clamp_to<std::uint16_t>(est.gps_hdop * 100.0);
      m.epv = m.eph;
      const double ground = std::hypot(v.x(), v.y());
      m.vel = clamp_to<std::uint16_t>(ground * 100.0);
      double cog = std::atan2(v.y(), v.x()) * kRadToDeg;
      if (cog < 0) cog += 360.0;
      m.cog = clamp_to<std::uint16_t>(std::fmod(cog * 100.0, 36000.0));
      m.satellites_visible = static_cast<std::uint8_t>(std::clamp(est.gps_satellites, 0, 255));
      m.alt_ellipsoid = m.alt;
      send(link, m);
      return true;
    }
    case msg::Attitude::kId: {
      const frames::Euler e = frames::euler_from_q_ned_frd(frames::q_ned_frd_from_q_enu_flu(est.q_enu_body));
      const Eigen::Vector3d w = frames::frd_from_flu(est.rate_body_rad_s);
      msg::Attitude m;
      m.time_boot_ms = t_ms;
      m.roll = static_cast<float>(e.roll_rad);
      m.pitch = static_cast<float>(e.pitch_rad);
      m.yaw = static_cast<float>(e.yaw_rad);
      m.rollspeed = static_cast<float>(w.x());
      m.pitchspeed = static_cast<float>(w.y());
      m.yawspeed = static_cast<float>(w.z());
      send(link, m);
      return true;
    }
    case msg::AttitudeQuaternion::kId: {
      const Eigen::Quaterniond q = frames::q_ned_frd_from_q_enu_flu(est.q_enu_body);
      const Eigen::Vector3d w = frames::frd_from_flu(est.rate_body_rad_s);
      msg::AttitudeQuaternion m;
      m.time_boot_ms = t_ms;
      m.q1 = static_cast<float>(q.w());
      m.q2 = static_cast<float>(q.x());
      m.q3 = static_cast<float>(q.y());
      m.q4 = static_cast<float>(q.z());
      m.rollspeed = static_cast<float>(w.x());
      m.pitchspeed = static_cast<float>(w.y());
      m.yawspeed = static_cast<float>(w.z());
      send(link, m);
      return true;
    }
    case msg::LocalPositionNed::kId: {
      const Eigen::Vector3d p = frames::ned_from_enu(est.position_enu_m);
      const Eigen::Vector3d v = frames::ned_from_enu(est.velocity_enu_m_s);
      msg::LocalPositionNed m;
      m.time_boot_ms = t_ms;
      m.x = static_cast<float>(p.x());
      m.y = static_cast<float>(p.y());
      m.z = static_cast<float>(p.z());
      m.vx = static_cast<float>(v.x());
      m.vy = static_cast<float>(v.y());
      m.vz = static_cast<float>(v.z());
      send(link, m);
      return true;
    }
    case msg::GlobalPositionInt::kId: {
      const Geodetic g = geodetic_of_enu(est.position_enu_m);
      const Eigen::Vector3d v = frames::ned_from_enu(est.velocity_enu_m_s);
      const double yaw =
          frames::euler_from_q_ned_frd(frames::q_ned_frd_from_q_enu_flu(est.q_enu_body)).yaw_rad * kRadToDeg;
      msg::GlobalPositionInt m;
      m.time_boot_ms = t_ms;
      m.lat = deg_e7(g.lat_deg);
      m.lon = deg_e7(g.lon_deg);
      m.alt = clamp_to<std::int32_t>(g.alt_m * 1000.0);
      const double home_up = fc.home_set() ? fc.home_enu_m().z() : 0.0;
      m.relative_alt = clamp_to<std::int32_t>((est.position_enu_m.z() - home_up) * 1000.0);
      m.vx = clamp_to<std::int16_t>(v.x() * 100.0);
      m.vy = clamp_to<std::int16_t>(v.y() * 100.0);
      m.vz = clamp_to<std::int16_t>(v.z() * 100.0);
      m.hdg = static_cast<std::uint16_t>(std::llround(std::fmod(yaw + 360.0, 360.0) * 100.0) % 36000);
      send(link, m);
      return true;
    }
    case msg::MissionCurrent::kId:
      send(link, mission_current());
      return true;
    case msg::VfrHud::kId: {
      const Geodetic g = geodetic_of_enu(est.position_enu_m);
      const double yaw =
          frames::euler_from_q_ned_frd(frames::q_ned_frd_from_q_enu_flu(est.q_enu_body)).yaw_rad * kRadToDeg;
      const auto& cmd = sim_.runtime(vehicle_).motor_cmd;
      double throttle = 0.0;
      for (double c : cmd) throttle += c;
      if (!cmd.empty()) throttle /= static_cast<double>(cmd.size());
      msg::VfrHud m;
      m.groundspeed = static_cast<float>(est.velocity_enu_m_s.head<2>().norm());
      m.airspeed = m.groundspeed;
      m.alt = static_cast<float>(g.alt_m);
      m.climb = static_cast<float>(est.velocity_enu_m_s.z());
      m.heading = static_cast<std::int16_t>(std::llround(std::fmod(yaw + 360.0, 360.0)) % 360);
      m.throttle = clamp_to<std::uint16_t>(throttle * 100.0);
      send(link, m);
      return true;
    }
    case msg::PositionTargetLocalNed::kId: {
      const auto target = fc.current_target();
      if (!target) return true;  // nothing to report outside guided control
      msg::PositionTargetLocalNed m;
      m.time_boot_ms = t_ms;
      m.coordinate_frame = field<std::uint8_t>(MavFrame::LocalNed);
      using Ignore = PositionTargetTypemask;
      std::uint16_t mask = 0;
      if (target->position_enu_m) {
        const Eigen::Vector3d p = frames::ned_from_enu(*target->position_enu_m);
        m.x = static_cast<float>(p.x()), m.y = static_cast<float>(p.y()), m.z = static_cast<float>(p.z());
      } else {
        mask |= field<std::uint16_t>({Ignore::XIgnore, Ignore::YIgnore, Ignore::ZIgnore});
      }
      if (target->velocity_enu_m_s) {
        const Eigen::Vector3d v = frames::ned_from_enu(*target->velocity_enu_m_s);
        m.vx = static_cast<float>(v.x()), m.vy = static_cast<float>(v.y()), m.vz = static_cast<float>(v.z());
      } else {
        mask |= field<std::uint16_t>({Ignore::VxIgnore, Ignore::VyIgnore, Ignore::VzIgnore});
      }
      if (target->accel_enu_m_s2) {
        const Eigen::Vector3d a = frames::ned_from_enu(*target->accel_enu_m_s2);
        m.afx = static_cast<float>(a.x()), m.afy = static_cast<float>(a.y()), m.afz = static_cast<float>(a.z());
      } else {
        mask |= field<std::uint16_t>({Ignore::AxIgnore, Ignore::AyIgnore, Ignore::AzIgnore});
      }
      if (target->yaw_enu_rad) {
        m.yaw = static_cast<float>(frames::yaw_ned_from_yaw_enu(*target->yaw_enu_rad));
      } else {
        mask |= field<std::uint16_t>(Ignore::YawIgnore);
      }
      if (target->yaw_rate_rad_s) {
        m.yaw_rate = static_cast<float>(-*target->yaw_rate_rad_s);
      } else {
        mask |= field<std::uint16_t>(Ignore::YawRateIgnore);
      }
      m.type_mask = mask;
      send(link, m);
      return true;
    }
    case msg::BatteryStatus::kId: {
      const airframe::BatteryState& b = sim_.runtime(vehicle_).battery;
      msg::BatteryStatus m;
      m.id = 0;
      m.battery_function = field<std::uint8_t>(MavBatteryFunction::Unknown);
      m.type = field<std::uint8_t>(MavBatteryType::Unknown);
      m.temperature = std::numeric_limits<std::int16_t>::max();  // unknown
      m.voltages.fill(std::numeric_limits<std::uint16_t>::max());
      m.voltages[0] = clamp_to<std::uint16_t>(b.voltage_v * 1000.0);
      m.current_battery = clamp_to<std::int16_t>(b.current_a * 100.0);
      m.current_consumed = clamp_to<std::int32_t>(b.consumed_mah);
      m.energy_consumed = -1;
      m.battery_remaining = clamp_to<std::int8_t>(
          100.0 * airframe::battery_remaining(sim_.airframe(vehicle_), b));
      send(link, m);
      return true;
    }
    case msg::EkfStatusReport::kId: {
      msg::EkfStatusReport m;
      // attitude, velocities, relative and absolute horizontal/vertical position, predicted positions
      using Ekf = EkfStatusFlags;
      m.flags = est.gps_ok ? field<std::uint16_t>({Ekf::Attitude, Ekf::VelocityHoriz, Ekf::VelocityVert,
                                                   Ekf::PosHorizRel, Ekf::PosHorizAbs, Ekf::PosVertAbs,
                                                   Ekf::PredPosHorizRel, Ekf::PredPosHorizAbs})
                           : field<std::uint16_t>({Ekf::Attitude, Ekf::VelocityHoriz, Ekf::VelocityVert,
                                                   Ekf::ConstPosMode});
      m.velocity_variance = m.pos_horiz_variance = m.pos_vert_variance = m.compass_variance = 0.05f;
      send(link, m);
      return true;
    }
    case msg::HomePosition::kId:
      send_home(link);
      return true;
    case msg::GpsGlobalOrigin::kId: {
      msg::GpsGlobalOrigin m;
      m.latitude = deg_e7(config_.origin.lat_deg);
      m.longitude = deg_e7(config_.origin.lon_deg);
      m.altitude = clamp_to<std::int32_t>(config_.origin.alt_m * 1000.0);
      m.time_usec = static_cast<std::uint64_t>(std::llround(now_s() * 1e6));
      send(link, m);
      return true;
    }
    case msg::ExtendedSysState::kId: {
      msg::ExtendedSysState m;
      m.vtol_state = field<std::uint8_t>(MavVtolState::Undefined);
      m.landed_state = landed_state_number(fc.landed_state());
      send(link, m);
      return true;
    }
    case msg::MountStatus::kId: {
      msg::MountStatus m;
      m.pointing_a = clamp_to<std::int32_t>(gimbal_.pitch_deg * 100.0);
      m.pointing_b = clamp_to<std::int32_t>(gimbal_.roll_deg * 100.0);
      m.pointing_c = clamp_to<std::int32_t>(gimbal_.yaw_deg * 100.0);
      m.mount_mode = gimbal_.mount_mode;
      send(link, m);
      return true;
    }
    case msg::MountOrientation::kId:
    case msg::GimbalDeviceAttitudeStatus::kId: {
      // the camera's attitude as the gimbal device measures it (the simulated gimbal's, lag
      // included, where the server has one), roll and pitch relative to the horizon, yaw relative
      // to the heading; a yaw-locked command reports it in the earth frame, the heading added from
      // the estimate
      const double vehicle_yaw_deg =
          frames::euler_from_q_ned_frd(frames::q_ned_frd_from_q_enu_flu(est.q_enu_body)).yaw_rad * kRadToDeg;
      std::optional<GimbalDeviceAttitude> measured;
      if (config_.gimbal_attitude) measured = config_.gimbal_attitude(vehicle_);
      const GimbalDeviceAttitude a =
          measured.value_or(commanded_attitude(gimbal_, vehicle_yaw_deg));
      const double yaw_north_deg = wrap_180(a.yaw_deg + vehicle_yaw_deg);
      if (msgid == msg::MountOrientation::kId) {
        msg::MountOrientation m;
        m.time_boot_ms = t_ms;
        m.roll = static_cast<float>(a.roll_deg);
        m.pitch = static_cast<float>(a.pitch_deg);
        m.yaw = static_cast<float>(a.yaw_deg);
        m.yaw_absolute = static_cast<float>(yaw_north_deg);
        send(link, m);
        return true;
      }
      using Gimbal = GimbalDeviceFlags;
      const double q_yaw_deg = gimbal_.yaw_earth_frame ? yaw_north_deg : a.yaw_deg;
      // FRD attitude of the camera: yaw, then pitch, then roll (ZYX), w x y z
      const Eigen::Quaterniond q =
          Eigen::AngleAxisd(q_yaw_deg * kDegToRad, Eigen::Vector3d::UnitZ()) *
          Eigen::AngleAxisd(a.pitch_deg * kDegToRad, Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(a.roll_deg * kDegToRad, Eigen::Vector3d::UnitX());
      msg::GimbalDeviceAttitudeStatus m;
      m.time_boot_ms = t_ms;
      m.q = {static_cast<float>(q.w()), static_cast<float>(q.x()), static_cast<float>(q.y()),
             static_cast<float>(q.z())};
      // a measured attitude comes without its rates; the commanded rates otherwise
      constexpr float kUnknown = std::numeric_limits<float>::quiet_NaN();
      m.angular_velocity_x = measured ? kUnknown : 0.0f;
      m.angular_velocity_y =
          measured ? kUnknown : static_cast<float>(gimbal_.pitch_rate_deg_s * kDegToRad);
      m.angular_velocity_z =
          measured ? kUnknown : static_cast<float>(gimbal_.yaw_rate_deg_s * kDegToRad);
      m.flags = gimbal_.yaw_earth_frame
                    ? field<std::uint16_t>({Gimbal::RollLock, Gimbal::PitchLock, Gimbal::YawLock,
                                            Gimbal::YawInEarthFrame})
                    : field<std::uint16_t>({Gimbal::RollLock, Gimbal::PitchLock, Gimbal::YawInVehicleFrame});
      // the yaw between the two frames (q_earth = q_delta_yaw * q_vehicle): the vehicle's heading
      m.delta_yaw = static_cast<float>(vehicle_yaw_deg * kDegToRad);
      m.delta_yaw_velocity = kUnknown;
      m.gimbal_device_id = 1;  // the autopilot reports for its first (non-MAVLink) gimbal
      send(link, m);
      return true;
    }
    case msg::AutopilotVersion::kId:
      send_autopilot_version(link);
      return true;
    default:
      return false;
  }
}

}  // namespace uavsim::server::mavlink
