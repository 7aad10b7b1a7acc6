// Commands (COMMAND_LONG, COMMAND_INT, SET_MODE) and guided setpoints, with ArduCopter's semantics
// (behaviour.md §4-5). Commands are acked on the link they came from; setpoints are never acked.
#include <cmath>

#include "uavsim/common/frames.hpp"
#include "mavlink/input_limits.hpp"
#include "mavlink/vehicle_link.hpp"

namespace uavsim::server::mavlink {

namespace frames = ::uavsim::common::frames;

namespace {

constexpr std::uint8_t kAccepted = to_underlying(MavResult::Accepted);
constexpr std::uint8_t kDenied = to_underlying(MavResult::Denied);
constexpr std::uint8_t kUnsupported = to_underlying(MavResult::Unsupported);
constexpr std::uint8_t kFailed = to_underlying(MavResult::Failed);

constexpr double kDegToRad = common::kPi / 180.0;

// ArduPilot answers a refused arm, disarm or take-off with FAILED (behaviour.md §4)
std::uint8_t failed_unless_accepted(fc::CommandResult r) {
  if (r == fc::CommandResult::kAccepted) return kAccepted;
  return r == fc::CommandResult::kUnsupported ? kUnsupported : kFailed;
}

std::uint8_t mav_result(fc::CommandResult r) {
  switch (r) {
    case fc::CommandResult::kAccepted: return kAccepted;
    case fc::CommandResult::kDenied: return kDenied;
    case fc::CommandResult::kFailed: return kFailed;
    case fc::CommandResult::kUnsupported: return kUnsupported;
    case fc::CommandResult::kInvalid: return kDenied;
  }
  return kFailed;
}

// type_mask groups: any bit of a group set ignores the whole group (ArduCopter)
using Mask = PositionTargetTypemask;
constexpr std::uint16_t bits(Mask m) { return static_cast<std::uint16_t>(to_underlying(m)); }
constexpr std::uint16_t kPosMask = bits(Mask::XIgnore) | bits(Mask::YIgnore) | bits(Mask::ZIgnore);
constexpr std::uint16_t kVelMask = bits(Mask::VxIgnore) | bits(Mask::VyIgnore) | bits(Mask::VzIgnore);
constexpr std::uint16_t kAccMask = bits(Mask::AxIgnore) | bits(Mask::AyIgnore) | bits(Mask::AzIgnore);
constexpr std::uint16_t kForceSet = bits(Mask::ForceSet);
constexpr std::uint16_t kYawIgnore = bits(Mask::YawIgnore);
constexpr std::uint16_t kYawRateIgnore = bits(Mask::YawRateIgnore);


using limits::within;
using sim::checked_integer;

// MAVLink message ids are 24 bits
constexpr std::uint32_t kMaxMsgId = 0xFFFFFF;
// mission sequence numbers are uint16 on the wire
constexpr int kMaxSeq = 65535;

}  // namespace

void VehicleLink::ack_command(Link& link, const Frame& frame, std::uint16_t command, std::uint8_t result) {
  msg::CommandAck ack;
  ack.command = command;
  ack.result = result;
  ack.progress = 0;
  ack.result_param2 = 0;
  ack.target_system = frame.sysid;
  ack.target_component = frame.compid;
  send(link, ack);
}

std::uint8_t VehicleLink::handle_command(Link& link, const CommandArgs& c, fc::FlightController& fc) {
  const auto& p = c.p;
  switch (static_cast<MavCmd>(c.command)) {
    case MavCmd::ComponentArmDisarm: {
      if (p[0] == 1.0) {
        if (fc.armed()) return kAccepted;
        const bool force = p[1] == 2989.0 || p[1] == 21196.0;  // both magic values force arming
        return failed_unless_accepted(fc.arm(force));
      }
      if (p[0] == 0.0) {
        if (!fc.armed()) return kAccepted;
        return failed_unless_accepted(fc.disarm(p[1] == 21196.0));
      }
      return kUnsupported;
    }
    case MavCmd::DoSetMode: {  // also the SET_MODE message; needs CUSTOM_MODE_ENABLED
      // both are integers on the wire (SET_MODE); anything a uint8/uint32 cannot hold is refused
      const auto base_mode = checked_integer<std::uint8_t>(p[0]);
      const auto custom_mode = checked_integer<std::uint32_t>(p[1]);
      if (!base_mode || !custom_mode) return kDenied;
      if ((*base_mode & to_underlying(MavModeFlag::CustomModeEnabled)) == 0) return kFailed;
      const auto mode = fc::mode_from_number(*custom_mode);
      if (!mode) return kFailed;
      return mav_result(fc.set_mode(*mode));
    }
    case MavCmd::NavTakeoff: {  // COMMAND_LONG is GLOBAL_RELATIVE_ALT; COMMAND_INT must be too
      if (c.is_int && !is_one_of<MavFrame>(c.frame, {MavFrame::GlobalRelativeAlt, MavFrame::GlobalRelativeAltInt})) {
        return kDenied;
      }
      if (!within(p[6], limits::kPosition_m)) return kDenied;
      return failed_unless_accepted(fc.takeoff(p[6]));
    }
    case MavCmd::NavLand:
      return mav_result(fc.land());
    case MavCmd::NavReturnToLaunch:
      return mav_result(fc.rtl());
    case MavCmd::NavLoiterUnlim:
      return mav_result(fc.set_mode(fc::Mode::kLoiter));
    case MavCmd::ConditionYaw: {  // angle, rate, direction, relative
      if (!within(p[0], limits::kAngle_deg) || !sim::finite_in(p[1], 0.0, limits::kYawRate_deg_s) ||
          !std::isfinite(p[2]) || !std::isfinite(p[3])) {
        return kDenied;
      }
      const int dir = p[2] > 0 ? 1 : (p[2] < 0 ? -1 : 0);
      return mav_result(fc.condition_yaw(p[0], p[1], dir, p[3] != 0.0));
    }
    case MavCmd::DoChangeSpeed: {  // speed type (0..3), speed
      const auto type = checked_integer<int>(p[0], 0, 3);
      if (!type || !within(p[1], limits::kSpeed_m_s)) return kDenied;
      return mav_result(fc.change_speed(*type, p[1]));
    }
    case MavCmd::MissionStart: {  // first, last item (0, 0 = all)
      const auto first = checked_integer<int>(p[0], 0, kMaxSeq);
      const auto last = checked_integer<int>(p[1], 0, kMaxSeq);
      if (!first || !last) return kDenied;
      return mav_result(fc.mission_start(*first, *last));
    }
    case MavCmd::DoSetMissionCurrent: {
      const auto seq = checked_integer<int>(p[0], 0, kMaxSeq);
      if (!seq) return kDenied;
      return mav_result(fc.set_mission_current(*seq));
    }
    case MavCmd::DoReposition: {  // COMMAND_INT only: go to lat/lon/alt in GUIDED
      if (!c.is_int) return kUnsupported;
      // NaN altitude means "keep the current one" (MAVLink's convention); any other non-number is refused
      if (!limits::valid_lat_lon(c.x / 1e7, c.y / 1e7) ||
          (!std::isnan(p[6]) && !within(p[6], limits::kPosition_m))) {
        return kDenied;
      }
      if (fc.mode() != fc::Mode::kGuided) {
        const fc::CommandResult r = fc.set_mode(fc::Mode::kGuided);
        if (r != fc::CommandResult::kAccepted) return mav_result(r);
      }
      fc::GuidedTarget t;
      Eigen::Vector3d pos = fc.estimate().position_enu_m;
      if (c.x != 0 || c.y != 0) {
        const Eigen::Vector3d xy = enu_of_geodetic({c.x / 1e7, c.y / 1e7, config_.origin.alt_m});
        pos.x() = xy.x();
        pos.y() = xy.y();
      }
      if (std::isfinite(p[6])) {
        const bool amsl = is_one_of<MavFrame>(c.frame, {MavFrame::Global, MavFrame::GlobalInt});
        pos.z() = amsl ? p[6] - config_.origin.alt_m : fc.home_enu_m().z() + p[6];
      }
      t.position_enu_m = pos;
      return mav_result(fc.set_guided_target(t));
    }
    case MavCmd::DoMountControl: {  // pitch, roll, yaw (deg), mode in param7
      // NaN leaves an axis as it is; MAV_MOUNT_MODE is 0..6 (0 here also leaves the mode)
      for (int i : {0, 1, 2}) {
        if (!std::isnan(p[i]) && !within(p[i], limits::kAngle_deg)) return kDenied;
      }
      const auto mount_mode = std::isnan(p[6]) ? std::optional<std::uint8_t>(0)
                                               : checked_integer<std::uint8_t>(p[6], 0, 6);
      if (!mount_mode) return kDenied;
      if (std::isfinite(p[0])) gimbal_.pitch_deg = p[0];
      if (std::isfinite(p[1])) gimbal_.roll_deg = p[1];
      if (std::isfinite(p[2])) gimbal_.yaw_deg = p[2];
      if (*mount_mode > 0) gimbal_.mount_mode = *mount_mode;
      gimbal_.yaw_earth_frame = false;
      gimbal_.stamp_s = now_s();
      return kAccepted;
    }
    case MavCmd::DoGimbalManagerPitchyaw: {  // pitch, yaw (deg), rates (deg/s), flags
      // NaN leaves an angle as it is and means rate 0 / no flags
      for (int i : {0, 1}) {
        if (!std::isnan(p[i]) && !within(p[i], limits::kAngle_deg)) return kDenied;
      }
      for (int i : {2, 3}) {
        if (!std::isnan(p[i]) && !within(p[i], limits::kYawRate_deg_s)) return kDenied;
      }
      const auto flags = std::isnan(p[4]) ? std::optional<std::uint32_t>(0) : checked_integer<std::uint32_t>(p[4]);
      if (!flags) return kDenied;
      if (std::isfinite(p[0])) gimbal_.pitch_deg = p[0];
      if (std::isfinite(p[1])) gimbal_.yaw_deg = p[1];
      gimbal_.pitch_rate_deg_s = std::isfinite(p[2]) ? p[2] : 0.0;
      gimbal_.yaw_rate_deg_s = std::isfinite(p[3]) ? p[3] : 0.0;
      gimbal_.yaw_earth_frame = (*flags & to_underlying(GimbalManagerFlags::YawLock)) != 0;
      gimbal_.mount_mode = to_underlying(MavMountMode::MavlinkTargeting);
      gimbal_.stamp_s = now_s();
      return kAccepted;
    }
    case MavCmd::GetHomePosition:
      if (!fc.home_set()) return kFailed;
      send_home(link);
      send_message_by_id(link, msg::GpsGlobalOrigin::kId);
      return kAccepted;
    case MavCmd::RequestAutopilotCapabilities:
      if (p[0] == 1.0) send_autopilot_version(link);
      return kAccepted;
    case MavCmd::RequestMessage: {  // sent at the next control step, after this ack
      const auto id = checked_integer<std::uint32_t>(p[0], 0, kMaxMsgId);
      if (!id) return kDenied;
      if (!can_send(*id)) return kFailed;
      link.one_shot.push_back(*id);
      return kAccepted;
    }
    case MavCmd::SetMessageInterval: {  // msgid, interval us (0 default, -1 stop)
      const auto id = checked_integer<std::uint32_t>(p[0], 0, kMaxMsgId);
      if (!id || !std::isfinite(p[1])) return kDenied;
      Stream* stream = nullptr;
      for (Stream& s : link.streams) {
        if (s.msgid == *id) stream = &s;
      }
      if (stream == nullptr) return kFailed;
      double interval_s = 0.0;
      if (p[1] == 0.0) {
        if (stream->default_interval_s <= 0.0) return kFailed;
        interval_s = stream->default_interval_s;
      } else if (p[1] < 0.0) {
        interval_s = 0.0;
      } else {
        interval_s = std::clamp(p[1] * 1e-6, 1e-3, 60.0);
      }
      stream->interval_s = interval_s;
      stream->next_due_s = now_s();  // first one at the next control step
      return kAccepted;
    }
    case MavCmd::GetMessageInterval: {  // -> MESSAGE_INTERVAL
      const auto checked_id = checked_integer<std::uint32_t>(p[0], 0, kMaxMsgId);
      if (!checked_id) return kDenied;
      const std::uint32_t id = *checked_id;
      msg::MessageInterval mi;
      mi.message_id = static_cast<std::uint16_t>(id);
      mi.interval_us = 0;  // not available
      for (const Stream& s : link.streams) {
        if (s.msgid == id) mi.interval_us = s.interval_s > 0 ? static_cast<std::int32_t>(s.interval_s * 1e6) : -1;
      }
      send(link, mi);
      return kAccepted;
    }
    case MavCmd::DoSendBanner:
      send_status_text(to_underlying(MavSeverity::Info), "ArduCopter V4.5.0 (uavsim)");
      return kAccepted;
    default:
      return kUnsupported;
  }
}

void VehicleLink::hold_position(fc::FlightController& fc) {
  // ArduCopter re-initialises guided mode (hold where it is) on an unusable setpoint frame
  fc::GuidedTarget t;
  t.position_enu_m = fc.estimate().position_enu_m;
  fc.set_guided_target(t);
}

void VehicleLink::apply_setpoint(std::uint16_t mask, int frame, std::optional<Eigen::Vector3d> pos_ned,
                                 const Eigen::Vector3d& vel_ned_in, const Eigen::Vector3d& acc_ned_in,
                                 double yaw_ned, double yaw_rate_ned, fc::FlightController& fc) {
  const bool use_pos = (mask & kPosMask) == 0 && pos_ned.has_value();
  const bool use_vel = (mask & kVelMask) == 0;
  const bool use_acc = (mask & kAccMask) == 0;
  const bool use_yaw = (mask & kYawIgnore) == 0;
  const bool use_yaw_rate = (mask & kYawRateIgnore) == 0;
  // FORCE_SET with an acceleration is a force setpoint, which ArduCopter refuses
  if ((mask & kForceSet) != 0 && use_acc) {
    StatCounters::add(stats_.rejected_inputs);
    return;
  }
  const fc::EstimatedState& est = fc.estimate();
  const double yaw_now_ned =
      frames::euler_from_q_ned_frd(frames::q_ned_frd_from_q_enu_flu(est.q_enu_body)).yaw_rad;
  const bool body = is_one_of<MavFrame>(frame, {MavFrame::BodyNed, MavFrame::BodyOffsetNed});
  // relative to the current position
  const bool offset =
      is_one_of<MavFrame>(frame, {MavFrame::LocalOffsetNed, MavFrame::BodyNed, MavFrame::BodyOffsetNed});
  Eigen::Vector3d vel_ned = vel_ned_in, acc_ned = acc_ned_in;
  // sanity: every used field finite and of a size a vehicle could be asked for
  if ((use_vel && (!within(vel_ned, limits::kSpeed_m_s) || vel_ned.norm() > limits::kSpeed_m_s)) ||
      (use_acc && !within(acc_ned, limits::kAccel_m_s2)) || (use_pos && !within(*pos_ned, limits::kPosition_m)) ||
      (use_yaw && !within(yaw_ned, limits::kYaw_rad)) ||
      (use_yaw_rate && !within(yaw_rate_ned, limits::kRate_rad_s))) {
    StatCounters::add(stats_.rejected_inputs);
    return;
  }
  fc::GuidedTarget t;
  if (use_pos) {
    Eigen::Vector3d p = body ? frames::ned_from_body_yaw(*pos_ned, yaw_now_ned) : *pos_ned;
    if (offset) p += frames::ned_from_enu(est.position_enu_m);
    t.position_enu_m = frames::enu_from_ned(p);
  }
  if (use_vel) {
    if (body) vel_ned = frames::ned_from_body_yaw(vel_ned, yaw_now_ned);
    t.velocity_enu_m_s = frames::enu_from_ned(vel_ned);
  }
  if (use_acc) {
    if (body) acc_ned = frames::ned_from_body_yaw(acc_ned, yaw_now_ned);
    t.accel_enu_m_s2 = frames::enu_from_ned(acc_ned);
  }
  if (use_yaw) t.yaw_enu_rad = frames::yaw_enu_from_yaw_ned(body ? yaw_ned + yaw_now_ned : yaw_ned);
  if (use_yaw_rate) t.yaw_rate_rad_s = -yaw_rate_ned;
  // dispatch as ArduCopter: pos(+vel)(+acc), vel(+acc), acc, pos; anything else (e.g. yaw only) holds
  if (!t.position_enu_m && !t.velocity_enu_m_s && !t.accel_enu_m_s2) {
    hold_position(fc);
    return;
  }
  if (fc.set_guided_target(t) != fc::CommandResult::kAccepted) StatCounters::add(stats_.rejected_inputs);
}

void VehicleLink::handle_set_position_target_local(const msg::SetPositionTargetLocalNed& m,
                                                   fc::FlightController& fc) {
  const int frame = m.coordinate_frame;
  if (!is_one_of<MavFrame>(
          frame, {MavFrame::LocalNed, MavFrame::LocalOffsetNed, MavFrame::BodyNed, MavFrame::BodyOffsetNed})) {
    hold_position(fc);
    return;
  }
  apply_setpoint(m.type_mask, frame, Eigen::Vector3d(m.x, m.y, m.z), Eigen::Vector3d(m.vx, m.vy, m.vz),
                 Eigen::Vector3d(m.afx, m.afy, m.afz), m.yaw, m.yaw_rate, fc);
}

void VehicleLink::handle_set_position_target_global(const msg::SetPositionTargetGlobalInt& m,
                                                    fc::FlightController& fc) {
  const int frame = m.coordinate_frame;
  const bool amsl = is_one_of<MavFrame>(frame, {MavFrame::Global, MavFrame::GlobalInt});
  const bool relative = is_one_of<MavFrame>(frame, {MavFrame::GlobalRelativeAlt, MavFrame::GlobalRelativeAltInt,
                                         MavFrame::GlobalTerrainAlt,  // terrain treated as relative
                                         MavFrame::GlobalTerrainAltInt});
  if (!amsl && !relative) {
    hold_position(fc);
    return;
  }
  std::optional<Eigen::Vector3d> pos_ned;
  if ((m.type_mask & kPosMask) == 0) {
    const double lat = m.lat_int / 1e7, lon = m.lon_int / 1e7;
    if (!limits::valid_lat_lon(lat, lon) || !within(m.alt, limits::kPosition_m)) {
      hold_position(fc);
      return;
    }
    const double alt_amsl = amsl ? m.alt : config_.origin.alt_m + fc.home_enu_m().z() + m.alt;
    pos_ned = ned_from_geodetic(config_.origin, {lat, lon, alt_amsl});
  }
  apply_setpoint(m.type_mask, 1, pos_ned, Eigen::Vector3d(m.vx, m.vy, m.vz), Eigen::Vector3d(m.afx, m.afy, m.afz),
                 m.yaw, m.yaw_rate, fc);
}

void VehicleLink::handle_set_attitude_target(const msg::SetAttitudeTarget& m, fc::FlightController& fc) {
  fc::AttitudeTarget t;
  // type_mask: 1/2/4 ignore body rates, 128 ignores the attitude
  if ((m.type_mask & 128) == 0) {
    const Eigen::Quaterniond q_ned_frd(m.q[0], m.q[1], m.q[2], m.q[3]);
    // each component of a unit quaternion is within [-1, 1]; allow slack for unnormalised senders
    const bool sane = (q_ned_frd.coeffs().array().abs() <= 2.0).all();
    if (!sane || q_ned_frd.norm() < 1e-6) {
      StatCounters::add(stats_.rejected_inputs);
      return;
    }
    t.q_enu_body = frames::q_enu_flu_from_q_ned_frd(q_ned_frd.normalized());
  }
  if ((m.type_mask & 7) != 7) {
    const Eigen::Vector3d w_frd((m.type_mask & 1) ? 0.0 : m.body_roll_rate,
                                (m.type_mask & 2) ? 0.0 : m.body_pitch_rate,
                                (m.type_mask & 4) ? 0.0 : m.body_yaw_rate);
    if (!within(w_frd, limits::kRate_rad_s)) {
      StatCounters::add(stats_.rejected_inputs);
      return;
    }
    t.rate_body_rad_s = frames::flu_from_frd(w_frd);
  }
  if ((m.type_mask & 64) == 0 && std::isfinite(m.thrust)) t.thrust = std::clamp<double>(m.thrust, 0.0, 1.0);
  if (fc.set_attitude_target(t) != fc::CommandResult::kAccepted) StatCounters::add(stats_.rejected_inputs);
}

}  // namespace uavsim::server::mavlink
