#include "mavlink/command_mapper.hpp"

#include <cmath>

#include "mavlink/input_limits.hpp"
#include "uavsim/common/angles.hpp"
#include "uavsim/common/frames.hpp"
#include "uavsim/common/mavlink/force_arm.hpp"
#include "uavsim/common/mavlink/generated/enums.hpp"

namespace uavsim::server::mavlink {

namespace frames = ::uavsim::common::frames;
using namespace ::uavsim::common::mavlink;
using limits::within;
using sim::checked_integer;

namespace {

constexpr std::uint8_t kAccepted = to_underlying(MavResult::Accepted);
constexpr std::uint8_t kDenied = to_underlying(MavResult::Denied);
constexpr std::uint8_t kUnsupported = to_underlying(MavResult::Unsupported);
constexpr std::uint8_t kFailed = to_underlying(MavResult::Failed);

using common::kDegToRad;

// MAVLink message ids are 24 bits
constexpr std::uint32_t kMaxMsgId = 0xFFFFFF;
// mission sequence numbers are uint16 on the wire
constexpr int kMaxSeq = 65535;

MappedCommand answer(std::uint8_t result) { return {std::nullopt, result}; }
MappedCommand to_fc(FcRequest r) { return {CommandRequest(std::move(r)), kAccepted}; }
MappedCommand to_gimbal(GimbalRequest r) { return {CommandRequest(std::move(r)), kAccepted}; }
MappedCommand to_link(LinkRequest r) { return {CommandRequest(std::move(r)), kAccepted}; }

// a finite angle as given, NaN as "leave it"
std::optional<double> unless_nan(double v) {
  return std::isnan(v) ? std::nullopt : std::optional<double>(v);
}

std::uint8_t mav_result(fc::CommandResult r) {
  switch (r) {
    case fc::CommandResult::kAccepted:
      return kAccepted;
    case fc::CommandResult::kDenied:
      return kDenied;
    case fc::CommandResult::kFailed:
      return kFailed;
    case fc::CommandResult::kUnsupported:
      return kUnsupported;
    case fc::CommandResult::kInvalid:
      return kDenied;
  }
  return kFailed;
}

}  // namespace

CommandArgs command_args(const msg::CommandLong& m) {
  CommandArgs c;
  c.command = m.command;
  c.p = {m.param1, m.param2, m.param3, m.param4, m.param5, m.param6, m.param7};
  return c;
}

CommandArgs command_args(const msg::CommandInt& m) {
  CommandArgs c;
  c.command = m.command;
  c.is_int = true;
  c.frame = m.frame;
  c.x = m.x;
  c.y = m.y;
  c.p = {m.param1, m.param2, m.param3, m.param4, m.x / 1e7, m.y / 1e7, m.z};
  return c;
}

CommandArgs command_args(const msg::SetMode& m) {
  CommandArgs c;
  c.command = to_underlying(MavCmd::DoSetMode);  // the same path as the command
  c.p[0] = m.base_mode;
  c.p[1] = m.custom_mode;
  return c;
}

MappedCommand map_command(const CommandArgs& c) {
  const auto& p = c.p;
  switch (static_cast<MavCmd>(c.command)) {
    case MavCmd::ComponentArmDisarm: {
      if (p[0] == 1.0)
        return to_fc(cmd::Arm{p[1] == kForceArmMagic || p[1] == kForceArmDisarmMagic});
      if (p[0] == 0.0) return to_fc(cmd::Disarm{p[1] == kForceArmDisarmMagic});
      return answer(kUnsupported);
    }
    case MavCmd::DoSetMode: {  // also the SET_MODE message; needs CUSTOM_MODE_ENABLED
      // both are integers on the wire (SET_MODE); anything a uint8/uint32 cannot hold is refused
      const auto base_mode = checked_integer<std::uint8_t>(p[0]);
      const auto custom_mode = checked_integer<std::uint32_t>(p[1]);
      if (!base_mode || !custom_mode) return answer(kDenied);
      if ((*base_mode & to_underlying(MavModeFlag::CustomModeEnabled)) == 0) return answer(kFailed);
      const auto mode = fc::mode_from_number(*custom_mode);
      if (!mode) return answer(kFailed);
      return to_fc(cmd::SetMode{*mode});
    }
    case MavCmd::NavTakeoff: {  // COMMAND_LONG is GLOBAL_RELATIVE_ALT; COMMAND_INT must be too
      if (c.is_int && !is_one_of<MavFrame>(
                          c.frame, {MavFrame::GlobalRelativeAlt, MavFrame::GlobalRelativeAltInt})) {
        return answer(kDenied);
      }
      if (!within(p[6], limits::kPosition_m)) return answer(kDenied);
      return to_fc(cmd::Takeoff{p[6]});
    }
    case MavCmd::NavLand:
      return to_fc(cmd::Land{});
    case MavCmd::NavReturnToLaunch:
      return to_fc(cmd::Rtl{});
    case MavCmd::NavLoiterUnlim:
      return to_fc(cmd::SetMode{fc::Mode::kLoiter});
    case MavCmd::ConditionYaw: {  // angle (deg, 0 = north, clockwise), rate (deg/s), direction,
                                  // relative
      if (!within(p[0], limits::kAngle_deg) || !sim::finite_in(p[1], 0.0, limits::kYawRate_deg_s) ||
          !std::isfinite(p[2]) || !std::isfinite(p[3])) {
        return answer(kDenied);
      }
      // compass heading (0 north, clockwise) -> ENU yaw (0 east, counter-clockwise): yaw = 90 deg -
      // hdg; a relative turn clockwise (direction +1, or 0 = shortest, taken as +1) is a negative
      // ENU change
      cmd::Yaw y;
      y.yaw.relative = p[3] != 0.0;
      if (y.yaw.relative) {
        const int dir = p[2] < 0 ? -1 : 1;
        y.yaw.yaw_enu_rad = -(dir * p[0] * kDegToRad);
      } else {
        y.yaw.yaw_enu_rad = common::kPi / 2.0 - p[0] * kDegToRad;
      }
      y.yaw.rate_rad_s = p[1] * kDegToRad;
      return to_fc(y);
    }
    case MavCmd::DoChangeSpeed: {  // speed type (0 air, 1 ground, 2 climb, 3 descent), speed
      const auto type = checked_integer<int>(p[0], 0, 3);
      if (!type || !within(p[1], limits::kSpeed_m_s)) return answer(kDenied);
      // no wind reaches the controller's speed limits: airspeed is ground speed
      const fc::SpeedLimit limit = *type == 2   ? fc::SpeedLimit::kClimb
                                   : *type == 3 ? fc::SpeedLimit::kDescent
                                                : fc::SpeedLimit::kHorizontal;
      return to_fc(cmd::ChangeSpeed{limit, p[1]});
    }
    case MavCmd::MissionStart: {  // first, last item (0, 0 = all)
      const auto first = checked_integer<int>(p[0], 0, kMaxSeq);
      const auto last = checked_integer<int>(p[1], 0, kMaxSeq);
      if (!first || !last) return answer(kDenied);
      return to_fc(cmd::MissionStart{*first, *last});
    }
    case MavCmd::DoSetMissionCurrent: {
      const auto seq = checked_integer<int>(p[0], 0, kMaxSeq);
      if (!seq) return answer(kDenied);
      return to_fc(cmd::SetMissionCurrent{*seq});
    }
    case MavCmd::DoReposition: {  // COMMAND_INT only: go to lat/lon/alt in GUIDED
      if (!c.is_int) return answer(kUnsupported);
      // NaN altitude means "keep the current one" (MAVLink's convention); any other non-number is
      // refused
      if (!limits::valid_lat_lon(c.x / 1e7, c.y / 1e7) ||
          (!std::isnan(p[6]) && !within(p[6], limits::kPosition_m))) {
        return answer(kDenied);
      }
      cmd::Reposition r;
      if (c.x != 0 || c.y != 0) r.lat_lon = ::uavsim::common::Geodetic{c.x / 1e7, c.y / 1e7, 0.0};
      if (std::isfinite(p[6])) r.alt_m = p[6];
      r.amsl = is_one_of<MavFrame>(c.frame, {MavFrame::Global, MavFrame::GlobalInt});
      return to_fc(r);
    }
    case MavCmd::DoMountControl: {  // pitch, roll, yaw (deg), mode in param7
      // NaN leaves an axis as it is; MAV_MOUNT_MODE is 0..6 (0 here also leaves the mode)
      for (int i : {0, 1, 2}) {
        if (!std::isnan(p[i]) && !within(p[i], limits::kAngle_deg)) return answer(kDenied);
      }
      const auto mount_mode = std::isnan(p[6]) ? std::optional<std::uint8_t>(0)
                                               : checked_integer<std::uint8_t>(p[6], 0, 6);
      if (!mount_mode) return answer(kDenied);
      return to_gimbal(
          cmd::MountControl{unless_nan(p[0]), unless_nan(p[1]), unless_nan(p[2]), *mount_mode});
    }
    case MavCmd::DoGimbalManagerPitchyaw: {  // pitch, yaw (deg), rates (deg/s), flags
      // NaN leaves an angle as it is and means rate 0 / no flags
      for (int i : {0, 1}) {
        if (!std::isnan(p[i]) && !within(p[i], limits::kAngle_deg)) return answer(kDenied);
      }
      for (int i : {2, 3}) {
        if (!std::isnan(p[i]) && !within(p[i], limits::kYawRate_deg_s)) return answer(kDenied);
      }
      const auto flags =
          std::isnan(p[4]) ? std::optional<std::uint32_t>(0) : checked_integer<std::uint32_t>(p[4]);
      if (!flags) return answer(kDenied);
      cmd::GimbalPitchYaw g;
      g.pitch_deg = unless_nan(p[0]);
      g.yaw_deg = unless_nan(p[1]);
      g.pitch_rate_deg_s = std::isfinite(p[2]) ? p[2] : 0.0;
      g.yaw_rate_deg_s = std::isfinite(p[3]) ? p[3] : 0.0;
      g.yaw_lock = (*flags & to_underlying(GimbalManagerFlags::YawLock)) != 0;
      return to_gimbal(g);
    }
    case MavCmd::GetHomePosition:
      return to_link(cmd::SendHome{});
    case MavCmd::RequestAutopilotCapabilities:
      if (p[0] == 1.0) return to_link(cmd::SendAutopilotVersion{});
      return answer(kAccepted);
    case MavCmd::RequestMessage: {  // sent at the next control step, after this ack
      const auto id = checked_integer<std::uint32_t>(p[0], 0, kMaxMsgId);
      if (!id) return answer(kDenied);
      return to_link(cmd::RequestMessage{*id});
    }
    case MavCmd::SetMessageInterval: {  // msgid, interval us (0 default, -1 stop)
      const auto id = checked_integer<std::uint32_t>(p[0], 0, kMaxMsgId);
      if (!id || !std::isfinite(p[1])) return answer(kDenied);
      return to_link(cmd::SetMessageInterval{*id, p[1]});
    }
    case MavCmd::GetMessageInterval: {  // -> MESSAGE_INTERVAL
      const auto id = checked_integer<std::uint32_t>(p[0], 0, kMaxMsgId);
      if (!id) return answer(kDenied);
      return to_link(cmd::GetMessageInterval{*id});
    }
    case MavCmd::DoSendBanner:
      return to_link(cmd::SendBanner{});
    default:
      return answer(kUnsupported);
  }
}

std::uint8_t ack_result(const FcRequest& request, fc::CommandResult result) {
  // ArduPilot answers a refused arm, disarm or take-off with FAILED (docs/mavlink.md §4)
  const bool failed_unless_accepted = std::holds_alternative<cmd::Arm>(request) ||
                                      std::holds_alternative<cmd::Disarm>(request) ||
                                      std::holds_alternative<cmd::Takeoff>(request);
  if (!failed_unless_accepted) return mav_result(result);
  if (result == fc::CommandResult::kAccepted) return kAccepted;
  return result == fc::CommandResult::kUnsupported ? kUnsupported : kFailed;
}

std::uint8_t execute(const FcRequest& request, fc::FlightController& fc,
                     const ::uavsim::common::GeodeticOrigin& origin) {
  const auto result = [&request](fc::CommandResult r) { return ack_result(request, r); };
  return std::visit(
      Overloaded{
          [&](const cmd::Arm& a) { return fc.armed() ? kAccepted : result(fc.arm(a.force)); },
          [&](const cmd::Disarm& d) {
            return !fc.armed() ? kAccepted : result(fc.disarm(d.force));
          },
          [&](const cmd::SetMode& m) { return result(fc.set_mode(m.mode)); },
          [&](const cmd::Takeoff& t) { return result(fc.takeoff(t.altitude_above_home_m)); },
          [&](const cmd::Land&) { return result(fc.land()); },
          [&](const cmd::Rtl&) { return result(fc.rtl()); },
          [&](const cmd::Yaw& y) { return result(fc.set_yaw(y.yaw)); },
          [&](const cmd::ChangeSpeed& s) { return result(fc.change_speed(s.limit, s.speed_m_s)); },
          [&](const cmd::MissionStart& m) { return result(fc.mission_start(m.first, m.last)); },
          [&](const cmd::SetMissionCurrent& m) { return result(fc.set_mission_current(m.seq)); },
          [&](const cmd::Reposition& r) {
            if (fc.mode() != fc::Mode::kGuided) {
              const fc::CommandResult switched = fc.set_mode(fc::Mode::kGuided);
              if (switched != fc::CommandResult::kAccepted) return result(switched);
            }
            Eigen::Vector3d pos = fc.estimate().position_enu_m;
            if (r.lat_lon) {
              const Eigen::Vector3d xy = common::enu_from_geodetic(
                  origin, {r.lat_lon->lat_deg, r.lat_lon->lon_deg, origin.alt_m});
              pos.x() = xy.x();
              pos.y() = xy.y();
            }
            if (r.alt_m)
              pos.z() = r.amsl ? *r.alt_m - origin.alt_m : fc.home_enu_m().z() + *r.alt_m;
            fc::GuidedTarget t;
            t.position_enu_m = pos;
            return result(fc.set_guided_target(t));
          },
      },
      request);
}

void apply(const GimbalRequest& request, GimbalState& gimbal, double now_s) {
  std::visit(Overloaded{
                 [&](const cmd::MountControl& m) {
                   if (m.pitch_deg) gimbal.pitch_deg = *m.pitch_deg;
                   if (m.roll_deg) gimbal.roll_deg = *m.roll_deg;
                   if (m.yaw_deg) gimbal.yaw_deg = *m.yaw_deg;
                   if (m.mount_mode > 0) gimbal.mount_mode = m.mount_mode;
                   gimbal.yaw_earth_frame = false;
                 },
                 [&](const cmd::GimbalPitchYaw& g) {
                   if (g.pitch_deg) gimbal.pitch_deg = *g.pitch_deg;
                   if (g.yaw_deg) gimbal.yaw_deg = *g.yaw_deg;
                   gimbal.pitch_rate_deg_s = g.pitch_rate_deg_s;
                   gimbal.yaw_rate_deg_s = g.yaw_rate_deg_s;
                   gimbal.yaw_earth_frame = g.yaw_lock;
                   gimbal.mount_mode = to_underlying(MavMountMode::MavlinkTargeting);
                 },
             },
             request);
  gimbal.stamp_s = now_s;
}

}  // namespace uavsim::server::mavlink
