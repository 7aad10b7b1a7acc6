// Commands (COMMAND_LONG, COMMAND_INT, SET_MODE) and guided setpoints, with ArduCopter's semantics
// (docs/mavlink.md §4-5). Commands are read by the pure command mapper (command_mapper.hpp) and
// carried out here; they are acked on the link they came from. Setpoints are never acked.
#include <algorithm>
#include <cmath>
#include <cstdint>

#include "mavlink/input_limits.hpp"
#include "mavlink/vehicle_link.hpp"
#include "uavsim/common/angles.hpp"
#include "uavsim/common/frames.hpp"

namespace uavsim::server::mavlink {

namespace frames = ::uavsim::common::frames;

namespace {

constexpr std::uint8_t kAccepted = to_underlying(MavResult::Accepted);
constexpr std::uint8_t kFailed = to_underlying(MavResult::Failed);

// type_mask groups: any bit of a group set ignores the whole group (ArduCopter)
using Mask = PositionTargetTypemask;
constexpr std::uint16_t bits(Mask m) { return static_cast<std::uint16_t>(to_underlying(m)); }
constexpr std::uint16_t kPosMask = bits(Mask::XIgnore) | bits(Mask::YIgnore) | bits(Mask::ZIgnore);
constexpr std::uint16_t kVelMask = bits(Mask::VxIgnore) | bits(Mask::VyIgnore) | bits(Mask::VzIgnore);
constexpr std::uint16_t kAccMask = bits(Mask::AxIgnore) | bits(Mask::AyIgnore) | bits(Mask::AzIgnore);
constexpr std::uint16_t kForceSet = bits(Mask::ForceSet);
constexpr std::uint16_t kYawIgnore = bits(Mask::YawIgnore);
constexpr std::uint16_t kYawRateIgnore = bits(Mask::YawRateIgnore);

// SET_ATTITUDE_TARGET's type_mask: each bit ignores one part of the target
using AttitudeMask = AttitudeTargetTypemask;
constexpr bool ignores(std::uint8_t type_mask, AttitudeMask part) {
  return (type_mask & to_underlying(part)) != 0;
}

using limits::within;

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
  const MappedCommand mapped = map_command(c);
  if (!mapped.request) return mapped.result;
  return std::visit(
      Overloaded{
          [&](const FcRequest& r) { return execute(r, fc, config_.origin); },
          [&](const GimbalRequest& r) {
            apply(r, gimbal_, now_s());
            return kAccepted;
          },
          [&](const LinkRequest& r) { return handle_link_request(link, r, fc); },
      },
      *mapped.request);
}

std::uint8_t VehicleLink::handle_link_request(Link& link, const LinkRequest& request, fc::FlightController& fc) {
  return std::visit(
      Overloaded{
          [&](const cmd::SendHome&) {
            if (!fc.home_set()) return kFailed;
            send_home(link);
            send_message_by_id(link, msg::GpsGlobalOrigin::kId);
            return kAccepted;
          },
          [&](const cmd::SendAutopilotVersion&) {
            send_autopilot_version(link);
            return kAccepted;
          },
          [&](const cmd::RequestMessage& r) {  // sent at the next control step, after this ack
            if (!can_send(r.msgid)) return kFailed;
            link.one_shot.push_back(r.msgid);
            return kAccepted;
          },
          [&](const cmd::SetMessageInterval& r) {
            return link.streams.set_interval(r.msgid, r.interval_us, now_s()) ? kAccepted : kFailed;
          },
          [&](const cmd::GetMessageInterval& r) {
            msg::MessageInterval mi;
            mi.message_id = static_cast<std::uint16_t>(r.msgid);
            mi.interval_us = link.streams.interval_us(r.msgid);
            send(link, mi);
            return kAccepted;
          },
          [&](const cmd::SendBanner&) {
            send_status_text(to_underlying(MavSeverity::Info), "ArduCopter V4.5.0 (uavsim)");
            return kAccepted;
          },
      },
      request);
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
      StatCounters::add(stats_.rejected_inputs);  // counted like the local setpoint's bad fields
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
  if (!ignores(m.type_mask, AttitudeMask::AttitudeIgnore)) {
    const Eigen::Quaterniond q_ned_frd(m.q[0], m.q[1], m.q[2], m.q[3]);
    // each component of a unit quaternion is within [-1, 1]; allow slack for unnormalised senders
    const bool sane = (q_ned_frd.coeffs().array().abs() <= 2.0).all();
    if (!sane || q_ned_frd.norm() < 1e-6) {
      StatCounters::add(stats_.rejected_inputs);
      return;
    }
    t.q_enu_body = frames::q_enu_flu_from_q_ned_frd(q_ned_frd.normalized());
  }
  // the body rates unless all three are ignored; an ignored one is zero
  const bool ignores_roll_rate = ignores(m.type_mask, AttitudeMask::BodyRollRateIgnore);
  const bool ignores_pitch_rate = ignores(m.type_mask, AttitudeMask::BodyPitchRateIgnore);
  const bool ignores_yaw_rate = ignores(m.type_mask, AttitudeMask::BodyYawRateIgnore);
  if (!(ignores_roll_rate && ignores_pitch_rate && ignores_yaw_rate)) {
    const Eigen::Vector3d w_frd(ignores_roll_rate ? 0.0 : m.body_roll_rate,
                                ignores_pitch_rate ? 0.0 : m.body_pitch_rate,
                                ignores_yaw_rate ? 0.0 : m.body_yaw_rate);
    if (!within(w_frd, limits::kRate_rad_s)) {
      StatCounters::add(stats_.rejected_inputs);
      return;
    }
    t.rate_body_rad_s = frames::flu_from_frd(w_frd);
  }
  if (!ignores(m.type_mask, AttitudeMask::ThrottleIgnore)) {
    // a thrust the message says to use but that is no number: the whole target is refused, like a bad
    // rate or quaternion (it once fell back to the previous thrust silently)
    if (!std::isfinite(m.thrust)) {
      StatCounters::add(stats_.rejected_inputs);
      return;
    }
    t.thrust = std::clamp<double>(m.thrust, 0.0, 1.0);
  }
  if (fc.set_attitude_target(t) != fc::CommandResult::kAccepted) StatCounters::add(stats_.rejected_inputs);
}

void VehicleLink::handle_gimbal_pitchyaw(const msg::GimbalManagerSetPitchyaw& m) {
  using common::kRadToDeg;
  // NaN leaves an angle as it is (MAVLink's convention); anything else must be a sane number
  const auto bad = [](float v, double limit) { return !std::isnan(v) && !limits::within(v, limit); };
  if (bad(m.pitch, limits::kYaw_rad) || bad(m.yaw, limits::kYaw_rad) || bad(m.pitch_rate, limits::kRate_rad_s) ||
      bad(m.yaw_rate, limits::kRate_rad_s)) {
    StatCounters::add(stats_.rejected_inputs);
    return;
  }
  if (std::isfinite(m.pitch)) gimbal_.pitch_deg = m.pitch * kRadToDeg;
  if (std::isfinite(m.yaw)) gimbal_.yaw_deg = m.yaw * kRadToDeg;
  gimbal_.pitch_rate_deg_s = std::isfinite(m.pitch_rate) ? m.pitch_rate * kRadToDeg : 0.0;
  gimbal_.yaw_rate_deg_s = std::isfinite(m.yaw_rate) ? m.yaw_rate * kRadToDeg : 0.0;
  gimbal_.yaw_earth_frame = (m.flags & to_underlying(GimbalManagerFlags::YawLock)) != 0;
  gimbal_.stamp_s = now_s();
}

namespace {
constexpr std::uint8_t kSysidMyGcs = 255;  // ArduPilot's SYSID_MYGCS default
}  // namespace

void VehicleLink::handle_rc_override(const Frame& f, const msg::RcChannelsOverride& m, fc::FlightController& fc) {
  if (f.sysid != kSysidMyGcs) {
    StatCounters::add(stats_.unhandled_messages);
    return;
  }
  // channels 1-4 are roll, pitch, throttle, yaw (ArduCopter's RCMAP defaults) in microseconds; 0
  // releases a channel (centred, mid throttle: no radio behind it here), UINT16_MAX leaves it as it was
  const std::uint16_t pwm[4] = {m.chan1_raw, m.chan2_raw, m.chan3_raw, m.chan4_raw};
  fc::PilotInput in = pilot_;
  double* axis[4] = {&in.roll, &in.pitch, &in.throttle, &in.yaw};
  for (int k = 0; k < 4; ++k) {
    if (pwm[k] == UINT16_MAX) continue;
    if (pwm[k] != 0 && (pwm[k] < 800 || pwm[k] > 2200)) {
      StatCounters::add(stats_.rejected_inputs);
      return;
    }
    const double us = pwm[k] == 0 ? 1500.0 : std::clamp<double>(pwm[k], 1000.0, 2000.0);
    // channel 2 high is nose up (stick back); throttle runs 1000 (0) to 2000 (1)
    *axis[k] = k == 2 ? (us - 1000.0) / 1000.0 : (us - 1500.0) / 500.0 * (k == 1 ? -1.0 : 1.0);
  }
  if (fc.set_pilot_input(in, now_s()) != fc::CommandResult::kInvalid) pilot_ = in;
}

void VehicleLink::handle_manual_control(const Frame& f, const msg::ManualControl& m, fc::FlightController& fc) {
  if (f.sysid != kSysidMyGcs) {
    StatCounters::add(stats_.unhandled_messages);
    return;
  }
  // x forward, y right, r clockwise in [-1000, 1000], z throttle in [0, 1000] (ArduPilot's reading);
  // INT16_MAX marks an axis as unused: it keeps its value
  fc::PilotInput in = pilot_;
  const std::int16_t raw[4] = {m.y, m.x, m.z, m.r};
  double* axis[4] = {&in.roll, &in.pitch, &in.throttle, &in.yaw};
  for (int k = 0; k < 4; ++k) {
    if (raw[k] == INT16_MAX) continue;
    *axis[k] = k == 2 ? std::clamp(raw[k] / 1000.0, 0.0, 1.0) : std::clamp(raw[k] / 1000.0, -1.0, 1.0);
  }
  if (fc.set_pilot_input(in, now_s()) != fc::CommandResult::kInvalid) pilot_ = in;
}


}  // namespace uavsim::server::mavlink
