// The flight modes: what each ArduCopter mode asks of the cascade, and AUTO's mission sequencing,
// over the mode context alone (mode_context.hpp).
#include "fc/flight_modes.hpp"

#include <algorithm>
#include <cmath>

#include "fc/angles.hpp"
#include "fc/attitude_control.hpp"
#include "fc/mode_context.hpp"

namespace uavsim::server::fc {

namespace {

// BRAKE latches a position hold below this horizontal speed
constexpr double kBrakeHoldSpeedM_S = 0.2;
// CONDITION_YAW completes within this heading error
constexpr double kYawDoneRad = 5.0 * kPi / 180.0;
// GUIDED velocity targets: how far the integrated position target may lead the vehicle
constexpr double kGuidedLeashM = 2.0;

}  // namespace

FlightMode& FlightModes::of(Mode mode) {
  switch (mode) {
    case Mode::kStabilize:
      return stabilize;
    case Mode::kAltHold:
      return alt_hold;
    case Mode::kGuided:
      return guided;
    case Mode::kLoiter:
      return loiter;
    case Mode::kBrake:
      return brake;
    case Mode::kLand:
      return land;
    case Mode::kRtl:
      return rtl;
    case Mode::kAuto:
      return automatic;
  }
  return stabilize;
}

// --- STABILIZE
// -------------------------------------------------------------------------------------

void StabilizeMode::enter(ModeContext& c, bool flying) {
  // no pilot: hold level with the collective we had (idle on the ground)
  c.command().fixed_thrust_n = flying ? c.collective_n() : 0.0;
}

void StabilizeMode::update(ModeContext& c, double dt_s) {
  (void)dt_s;
  CascadeCommand& cmd = c.command();
  const std::optional<PilotInput> in = c.pilot();
  cmd.kind = ControlKind::kAttitude;
  cmd.attitude_climb = false;
  if (in) {
    // the sticks lean the vehicle; the throttle is the collective
    c.run_pilot_lean(*in);
    cmd.fixed_thrust_n = c.pilot_thrust_n(in->throttle);
  } else {
    cmd.q_attitude_target = attitude_from_thrust(Eigen::Vector3d::UnitZ(), c.yaw().cmd_rad, 0.0);
  }
}

// --- ALT_HOLD
// --------------------------------------------------------------------------------------

void AltHoldMode::update(ModeContext& c, double dt_s) {
  CascadeCommand& cmd = c.command();
  NavState& nav = c.nav();
  if (c.taking_off()) {
    c.run_nav(dt_s, c.nav_limits());
    nav.hold_position_enu_m = nav.carrot.destination();
    return;
  }
  PositionSetpoint& sp = cmd.setpoint;
  if (const std::optional<PilotInput> in = c.pilot()) {
    // the sticks lean the vehicle; the throttle is a climb rate
    c.run_pilot_lean(*in);
    c.run_pilot_climb(*in, dt_s);
    sp.use_pos_xy = false;
    sp.use_vel_xy = false;
    cmd.kind = ControlKind::kAttitude;
    cmd.attitude_climb = true;
    return;
  }
  // hold altitude; no horizontal control: level attitude
  sp.position_enu_m = nav.hold_position_enu_m;
  sp.velocity_enu_m_s.setZero();
  sp.accel_enu_m_s2.setZero();
  sp.use_pos_xy = false;
  sp.use_vel_xy = false;
  sp.use_pos_z = true;
  cmd.kind = ControlKind::kPosition;
}

// --- GUIDED
// ----------------------------------------------------------------------------------------

void GuidedMode::enter(ModeContext& c, bool flying) {
  if (flying) c.start_hold();
}

void GuidedMode::update(ModeContext& c, double dt_s) {
  const EstimatedState& est = c.estimate();
  const ParamValues& p = c.params();
  const DerivedParams& d = c.derived();
  CascadeCommand& cmd = c.command();
  PositionSetpoint& sp = cmd.setpoint;
  GuidedState& g = c.guided();
  YawState& yaw = c.yaw();
  const double since_cmd = c.now() - g.cmd_time_s;
  const GuidedTarget& t = g.target;
  const bool is_new = g.is_new;
  const bool reinit = g.reinit;
  g.is_new = false;
  g.reinit = false;
  switch (g.sub) {
    case GuidedSub::kHold:
    case GuidedSub::kTakeoff:
      c.run_nav(dt_s, c.nav_limits());
      if (g.sub == GuidedSub::kTakeoff && !c.taking_off()) g.sub = GuidedSub::kWp;
      break;
    case GuidedSub::kWp:
      c.face_destination();
      c.run_nav(dt_s, c.nav_limits());
      break;
    case GuidedSub::kPosVelAccel: {
      // the position target moves with the commanded velocity; velocity and accel time out
      const bool fresh = since_cmd < p.guid_timeout;
      if (is_new) sp.position_enu_m = *t.position_enu_m;
      sp.velocity_enu_m_s =
          fresh && t.velocity_enu_m_s ? *t.velocity_enu_m_s : Eigen::Vector3d::Zero();
      sp.accel_enu_m_s2 = fresh && t.accel_enu_m_s2 ? *t.accel_enu_m_s2 : Eigen::Vector3d::Zero();
      sp.position_enu_m += sp.velocity_enu_m_s * dt_s;
      sp.use_pos_xy = sp.use_pos_z = sp.use_vel_xy = true;
      cmd.kind = ControlKind::kPosition;
      break;
    }
    case GuidedSub::kVelAccel:
    case GuidedSub::kAccel: {
      if (since_cmd >= p.guid_timeout) {
        // ArduCopter: velocity/accel targets stop after GUID_TIMEOUT; then hold
        g.sub = GuidedSub::kHold;
        c.nav().active = false;
        c.start_hold();
        c.run_nav(dt_s, c.nav_limits());
        break;
      }
      if (reinit) {
        sp.position_enu_m = est.position_enu_m;
        sp.velocity_enu_m_s = est.velocity_enu_m_s;
      }
      c.nav().active = false;
      // shape the velocity target with WPNAV_ACCEL / WPNAV_ACCEL_Z so the integrated position
      // target does not run away from the vehicle (ArduCopter's input shaping)
      Eigen::Vector3d vel_cmd;
      if (g.sub == GuidedSub::kVelAccel) {
        vel_cmd = *t.velocity_enu_m_s;
        sp.accel_enu_m_s2 = t.accel_enu_m_s2 ? *t.accel_enu_m_s2 : Eigen::Vector3d::Zero();
      } else {
        sp.accel_enu_m_s2 = *t.accel_enu_m_s2;
        vel_cmd = sp.velocity_enu_m_s + sp.accel_enu_m_s2 * dt_s;
      }
      Eigen::Vector3d dv = vel_cmd - sp.velocity_enu_m_s;
      const double dv_xy = dv.head<2>().norm(), dv_xy_max = d.wp_accel_m_s2 * dt_s;
      if (dv_xy > dv_xy_max) dv.head<2>() *= dv_xy_max / dv_xy;
      dv.z() = std::clamp(dv.z(), -d.wp_accel_z_m_s2 * dt_s, d.wp_accel_z_m_s2 * dt_s);
      sp.velocity_enu_m_s += dv;
      if (g.sub == GuidedSub::kVelAccel && !t.accel_enu_m_s2) sp.accel_enu_m_s2 = dv / dt_s;
      // the position target integrates the velocity, kept within a leash of the vehicle
      sp.position_enu_m += sp.velocity_enu_m_s * dt_s;
      Eigen::Vector3d lead = sp.position_enu_m - est.position_enu_m;
      if (lead.norm() > kGuidedLeashM) {
        sp.position_enu_m = est.position_enu_m + lead * (kGuidedLeashM / lead.norm());
      }
      sp.use_pos_xy = sp.use_pos_z = sp.use_vel_xy = true;
      cmd.kind = ControlKind::kPosition;
      break;
    }
    case GuidedSub::kAttitude: {
      const AttitudeTarget& a = g.attitude;
      const bool fresh = since_cmd < p.guid_timeout;
      // thrust 0.5 = hold climb rate 0; above/below scale to PILOT_SPEED_UP/DN (ArduCopter)
      const double thrust = fresh ? a.thrust : 0.5;
      const double climb = thrust >= 0.5 ? (thrust - 0.5) * 2.0 * d.pilot_speed_up_m_s
                                         : (thrust - 0.5) * 2.0 * d.pilot_speed_dn_m_s;
      sp.velocity_enu_m_s = Eigen::Vector3d(0.0, 0.0, climb);
      sp.accel_enu_m_s2.setZero();
      sp.use_pos_xy = sp.use_pos_z = sp.use_vel_xy = false;
      cmd.attitude_climb = true;
      c.nav().active = false;
      if (fresh && !a.q_enu_body && a.rate_body_rad_s) {
        cmd.kind = ControlKind::kBodyRate;
        cmd.rate_target_body_rad_s = *a.rate_body_rad_s;
        break;
      }
      cmd.kind = ControlKind::kAttitude;
      if (fresh && a.q_enu_body) {
        // keep the commanded heading; limit the lean to ANGLE_MAX
        const Eigen::Vector3d x_enu = *a.q_enu_body * Eigen::Vector3d::UnitX();
        const Eigen::Vector3d z_enu = *a.q_enu_body * Eigen::Vector3d::UnitZ();
        yaw.target_rad = std::atan2(x_enu.y(), x_enu.x());
        yaw.cmd_rad = yaw.target_rad;
        cmd.q_attitude_target = attitude_from_thrust(z_enu, yaw.target_rad, d.angle_max_rad);
      } else {
        cmd.q_attitude_target = attitude_from_thrust(Eigen::Vector3d::UnitZ(), yaw.cmd_rad, 0.0);
      }
      break;
    }
  }
}

// --- LOITER
// ----------------------------------------------------------------------------------------

void LoiterMode::enter(ModeContext& c, bool flying) {
  if (flying) c.start_hold();
}

void LoiterMode::update(ModeContext& c, double dt_s) {
  const std::optional<PilotInput> in = c.pilot();
  if (in && c.run_pilot_loiter(*in, dt_s)) return;
  c.run_nav(dt_s, c.nav_limits());
}

// --- BRAKE
// -----------------------------------------------------------------------------------------

void BrakeMode::enter(ModeContext& c, bool flying) {
  (void)c;
  (void)flying;
  holding_ = false;
}

void BrakeMode::update(ModeContext& c, double dt_s) {
  (void)dt_s;
  const EstimatedState& est = c.estimate();
  CascadeCommand& cmd = c.command();
  PositionSetpoint& sp = cmd.setpoint;
  Eigen::Vector3d& hold = c.nav().hold_position_enu_m;
  // stop at up to the lean limit, then hold where we stopped
  if (!holding_ && est.velocity_enu_m_s.head<2>().norm() < kBrakeHoldSpeedM_S) {
    holding_ = true;
    hold.head<2>() = est.position_enu_m.head<2>();
  }
  sp.position_enu_m = hold;
  sp.velocity_enu_m_s.setZero();
  sp.accel_enu_m_s2.setZero();
  sp.use_pos_xy = holding_;
  sp.use_vel_xy = true;
  sp.use_pos_z = true;
  cmd.kind = ControlKind::kPosition;
}

// --- LAND
// ------------------------------------------------------------------------------------------

void LandMode::enter(ModeContext& c, bool flying) {
  (void)flying;
  c.nav().land_xy_enu_m = c.nav().hold_position_enu_m;
}

void LandMode::update(ModeContext& c, double dt_s) {
  (void)dt_s;
  c.run_land_descent(c.estimate().gps_ok);
}

// --- RTL
// -------------------------------------------------------------------------------------------

void RtlMode::enter(ModeContext& c, bool flying) {
  if (flying) start(c);
}

void RtlMode::start(ModeContext& c) {
  const EstimatedState& est = c.estimate();
  // climb to RTL_ALT above home if lower, where we are; then fly home at that altitude
  alt_enu_m_ =
      std::max(est.position_enu_m.z(), c.home().position_enu_m.z() + c.derived().rtl_alt_m);
  stage_ = Stage::kClimb;
  c.nav().active = false;
  Eigen::Vector3d climb = c.stopping_point();
  climb.z() = alt_enu_m_;
  c.start_nav_to(climb);
}

void RtlMode::update(ModeContext& c, double dt_s) {
  const EstimatedState& est = c.estimate();
  const DerivedParams& d = c.derived();
  const Eigen::Vector3d& home = c.home().position_enu_m;
  NavState& nav = c.nav();
  NavLimits lim = c.nav_limits();
  switch (stage_) {
    case Stage::kClimb:
      c.run_nav(dt_s, lim);
      if (nav.carrot.arrived()) {
        stage_ = Stage::kReturn;
        c.start_nav_to(Eigen::Vector3d(home.x(), home.y(), alt_enu_m_));
      }
      break;
    case Stage::kReturn:
      lim.speed_xy_m_s = d.rtl_speed_m_s;
      c.run_nav(dt_s, lim);
      if (nav.carrot.arrived() &&
          (est.position_enu_m.head<2>() - home.head<2>()).norm() < d.wp_radius_m) {
        stage_ = Stage::kLoiter;
        loiter_start_s_ = c.now();
      }
      break;
    case Stage::kLoiter:
      c.run_nav(dt_s, lim);
      if (c.now() - loiter_start_s_ >= d.rtl_loit_time_s) {
        stage_ = Stage::kLand;
        nav.land_xy_enu_m = Eigen::Vector3d(home.x(), home.y(), 0.0);
      }
      break;
    case Stage::kLand:
      c.run_land_descent(est.gps_ok);
      break;
  }
}

// --- AUTO
// ------------------------------------------------------------------------------------------

void AutoMode::enter(ModeContext& c, bool flying) {
  (void)flying;
  const int size = static_cast<int>(c.mission().items.size());
  start_item(c, std::clamp(c.mission().current, 1, size - 1));
}

void AutoMode::start_item(ModeContext& c, int seq) {
  const EstimatedState& est = c.estimate();
  MissionState& mission = c.mission();
  NavState& nav = c.nav();
  mission.current = seq;
  const int size = static_cast<int>(mission.items.size());
  if (seq >= size || (mission.last > 0 && seq > mission.last)) {
    // end of mission: stay in AUTO and hold (ArduCopter MIS_DONE_BEHAVE = 0)
    mission.current = std::min(seq, size - 1);
    phase_ = Phase::kDone;
    if (c.armed() && !c.landed()) c.start_hold();
    c.status(6, "Mission complete");
    return;
  }
  const MissionItem& item = mission.items[static_cast<std::size_t>(seq)];
  phase_ = Phase::kNav;
  switch (item.kind) {
    case MissionItem::Kind::kTakeoff: {
      const double base_z = c.home().set ? c.home().position_enu_m.z() : est.position_enu_m.z();
      const double target_z = base_z + item.position_enu_m.z();
      if (c.landed() && c.armed()) {
        c.start_takeoff(target_z);
      } else {
        Eigen::Vector3d dest = nav.active ? nav.carrot.destination() : est.position_enu_m;
        dest.z() = std::max(target_z, est.position_enu_m.z());
        c.start_nav_to(dest);
      }
      break;
    }
    case MissionItem::Kind::kWaypoint:
    case MissionItem::Kind::kLoiterTime:
      c.start_nav_to(item.position_valid ? item.position_enu_m : est.position_enu_m);
      break;
    case MissionItem::Kind::kLand:
      if (item.position_valid) {
        c.start_nav_to(Eigen::Vector3d(item.position_enu_m.x(), item.position_enu_m.y(),
                                       est.position_enu_m.z()));
        phase_ = Phase::kLandApproach;
      } else {
        nav.land_xy_enu_m = c.stopping_point();
        phase_ = Phase::kLandDescend;
      }
      break;
    case MissionItem::Kind::kRtl:
      rtl_.start(c);
      phase_ = Phase::kRtl;
      break;
    case MissionItem::Kind::kChangeSpeed:
      if (item.param_s_or_m_s > 0.0 && std::isfinite(item.param_s_or_m_s)) {
        nav.speed_xy_override_m_s = item.param_s_or_m_s;
      }
      complete_item(c);
      break;
    case MissionItem::Kind::kConditionYaw:
      c.yaw().target_rad = wrap_pi(item.yaw_enu_rad);
      c.yaw().fixed = true;
      phase_ = Phase::kYaw;
      break;
  }
}

void AutoMode::complete_item(ModeContext& c) {
  MissionState& mission = c.mission();
  mission.reached.push(mission.current);
  start_item(c, mission.current + 1);
}

void AutoMode::update(ModeContext& c, double dt_s) {
  const EstimatedState& est = c.estimate();
  const DerivedParams& d = c.derived();
  const MissionState& mission = c.mission();
  const WaypointNav& carrot = c.nav().carrot;
  const MissionItem& item = mission.items[static_cast<std::size_t>(
      std::clamp(mission.current, 0, static_cast<int>(mission.items.size()) - 1))];
  // the carrot sits on its destination and the vehicle is within WP_RADIUS of it
  const auto within = [&] {
    return carrot.arrived() && (est.position_enu_m - carrot.destination()).norm() < d.wp_radius_m;
  };
  switch (phase_) {
    case Phase::kNav: {
      if (item.kind != MissionItem::Kind::kTakeoff) c.face_destination();
      c.run_nav(dt_s, c.nav_limits());
      if (item.kind == MissionItem::Kind::kTakeoff) {
        if (!c.taking_off() && carrot.arrived()) complete_item(c);
      } else if (within()) {
        if (item.param_s_or_m_s > 0.0) {
          phase_ = Phase::kHold;
          hold_start_s_ = c.now();
        } else {
          complete_item(c);
        }
      }
      break;
    }
    case Phase::kHold:
      c.run_nav(dt_s, c.nav_limits());
      if (c.now() - hold_start_s_ >= item.param_s_or_m_s) complete_item(c);
      break;
    case Phase::kLandApproach:
      c.face_destination();
      c.run_nav(dt_s, c.nav_limits());
      if (within()) {
        c.nav().land_xy_enu_m = carrot.destination();
        phase_ = Phase::kLandDescend;
      }
      break;
    case Phase::kLandDescend:
      c.run_land_descent(est.gps_ok);
      break;
    case Phase::kRtl:
      rtl_.update(c, dt_s);
      break;
    case Phase::kYaw:
      c.run_nav(dt_s, c.nav_limits());
      if (std::abs(wrap_pi(c.yaw().target_rad - c.yaw_enu_rad())) < kYawDoneRad) complete_item(c);
      break;
    case Phase::kDone:
      c.run_nav(dt_s, c.nav_limits());
      break;
  }
}

}  // namespace uavsim::server::fc
