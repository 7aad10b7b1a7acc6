// The flight modes: what each ArduCopter mode asks of the cascade, and AUTO's mission sequencing.
#include "fc/flight_modes.hpp"

#include <algorithm>
#include <cmath>

#include "fc/angles.hpp"
#include "fc/fc_impl.hpp"

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

void StabilizeMode::enter(Vehicle& v, bool flying) {
  // no pilot: hold level with the collective we had (idle on the ground)
  v.fixed_thrust_n_ = flying ? v.mixer_status_.thrust_n : 0.0;
}

void StabilizeMode::update(Vehicle& v, double dt_s) {
  (void)dt_s;
  const std::optional<PilotInput> in = v.pilot();
  v.control_ = ControlKind::kAttitude;
  v.attitude_climb_ = false;
  if (in) {
    // the sticks lean the vehicle; the throttle is the collective
    v.run_pilot_lean(*in);
    v.fixed_thrust_n_ = v.pilot_thrust_n(in->throttle);
  } else {
    v.q_attitude_target_ = attitude_from_thrust(Eigen::Vector3d::UnitZ(), v.yaw_cmd_rad_, 0.0);
  }
}

// --- ALT_HOLD
// --------------------------------------------------------------------------------------

void AltHoldMode::update(Vehicle& v, double dt_s) {
  if (v.takeoff_active_) {
    v.run_nav(dt_s, v.nav_limits());
    v.hold_position_enu_m_ = v.nav_.destination();
    return;
  }
  PositionSetpoint& sp = v.sp_;
  if (const std::optional<PilotInput> in = v.pilot()) {
    // the sticks lean the vehicle; the throttle is a climb rate
    v.run_pilot_lean(*in);
    v.run_pilot_climb(*in, dt_s);
    sp.use_pos_xy = false;
    sp.use_vel_xy = false;
    v.control_ = ControlKind::kAttitude;
    v.attitude_climb_ = true;
    return;
  }
  // hold altitude; no horizontal control: level attitude
  sp.position_enu_m = v.hold_position_enu_m_;
  sp.velocity_enu_m_s.setZero();
  sp.accel_enu_m_s2.setZero();
  sp.use_pos_xy = false;
  sp.use_vel_xy = false;
  sp.use_pos_z = true;
  v.control_ = ControlKind::kPosition;
}

// --- GUIDED
// ----------------------------------------------------------------------------------------

void GuidedMode::enter(Vehicle& v, bool flying) {
  if (flying) v.start_hold();
}

void GuidedMode::update(Vehicle& v, double dt_s) {
  const EstimatedState& est = v.estimator_.state();
  const ParamValues& p = v.params_.values();
  const DerivedParams& d = v.params_.derived();
  PositionSetpoint& sp = v.sp_;
  const double since_cmd = v.now() - v.guided_cmd_time_s_;
  const GuidedTarget& t = v.guided_target_;
  const bool is_new = v.guided_new_;
  const bool reinit = v.guided_reinit_;
  v.guided_new_ = false;
  v.guided_reinit_ = false;
  switch (v.guided_sub_) {
    case GuidedSub::kHold:
    case GuidedSub::kTakeoff:
      v.run_nav(dt_s, v.nav_limits());
      if (v.guided_sub_ == GuidedSub::kTakeoff && !v.takeoff_active_)
        v.guided_sub_ = GuidedSub::kWp;
      break;
    case GuidedSub::kWp:
      v.face_destination();
      v.run_nav(dt_s, v.nav_limits());
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
      v.control_ = ControlKind::kPosition;
      break;
    }
    case GuidedSub::kVelAccel:
    case GuidedSub::kAccel: {
      if (since_cmd >= p.guid_timeout) {
        // ArduCopter: velocity/accel targets stop after GUID_TIMEOUT; then hold
        v.guided_sub_ = GuidedSub::kHold;
        v.nav_active_ = false;
        v.start_hold();
        v.run_nav(dt_s, v.nav_limits());
        break;
      }
      if (reinit) {
        sp.position_enu_m = est.position_enu_m;
        sp.velocity_enu_m_s = est.velocity_enu_m_s;
      }
      v.nav_active_ = false;
      // shape the velocity target with WPNAV_ACCEL / WPNAV_ACCEL_Z so the integrated position
      // target does not run away from the vehicle (ArduCopter's input shaping)
      Eigen::Vector3d vel_cmd;
      if (v.guided_sub_ == GuidedSub::kVelAccel) {
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
      if (v.guided_sub_ == GuidedSub::kVelAccel && !t.accel_enu_m_s2) sp.accel_enu_m_s2 = dv / dt_s;
      // the position target integrates the velocity, kept within a leash of the vehicle
      sp.position_enu_m += sp.velocity_enu_m_s * dt_s;
      Eigen::Vector3d lead = sp.position_enu_m - est.position_enu_m;
      if (lead.norm() > kGuidedLeashM) {
        sp.position_enu_m = est.position_enu_m + lead * (kGuidedLeashM / lead.norm());
      }
      sp.use_pos_xy = sp.use_pos_z = sp.use_vel_xy = true;
      v.control_ = ControlKind::kPosition;
      break;
    }
    case GuidedSub::kAttitude: {
      const AttitudeTarget& a = v.attitude_target_;
      const bool fresh = since_cmd < p.guid_timeout;
      // thrust 0.5 = hold climb rate 0; above/below scale to PILOT_SPEED_UP/DN (ArduCopter)
      const double thrust = fresh ? a.thrust : 0.5;
      const double climb = thrust >= 0.5 ? (thrust - 0.5) * 2.0 * d.pilot_speed_up_m_s
                                         : (thrust - 0.5) * 2.0 * d.pilot_speed_dn_m_s;
      sp.velocity_enu_m_s = Eigen::Vector3d(0.0, 0.0, climb);
      sp.accel_enu_m_s2.setZero();
      sp.use_pos_xy = sp.use_pos_z = sp.use_vel_xy = false;
      v.attitude_climb_ = true;
      v.nav_active_ = false;
      if (fresh && !a.q_enu_body && a.rate_body_rad_s) {
        v.control_ = ControlKind::kBodyRate;
        v.rate_target_body_rad_s_ = *a.rate_body_rad_s;
        break;
      }
      v.control_ = ControlKind::kAttitude;
      if (fresh && a.q_enu_body) {
        // keep the commanded heading; limit the lean to ANGLE_MAX
        const Eigen::Vector3d x_enu = *a.q_enu_body * Eigen::Vector3d::UnitX();
        const Eigen::Vector3d z_enu = *a.q_enu_body * Eigen::Vector3d::UnitZ();
        v.yaw_target_rad_ = std::atan2(x_enu.y(), x_enu.x());
        v.yaw_cmd_rad_ = v.yaw_target_rad_;
        v.q_attitude_target_ = attitude_from_thrust(z_enu, v.yaw_target_rad_, d.angle_max_rad);
      } else {
        v.q_attitude_target_ = attitude_from_thrust(Eigen::Vector3d::UnitZ(), v.yaw_cmd_rad_, 0.0);
      }
      break;
    }
  }
}

// --- LOITER
// ----------------------------------------------------------------------------------------

void LoiterMode::enter(Vehicle& v, bool flying) {
  if (flying) v.start_hold();
}

void LoiterMode::update(Vehicle& v, double dt_s) {
  const std::optional<PilotInput> in = v.pilot();
  if (in && v.run_pilot_loiter(*in, dt_s)) return;
  v.run_nav(dt_s, v.nav_limits());
}

// --- BRAKE
// -----------------------------------------------------------------------------------------

void BrakeMode::enter(Vehicle& v, bool flying) {
  (void)v;
  (void)flying;
  holding_ = false;
}

void BrakeMode::update(Vehicle& v, double dt_s) {
  (void)dt_s;
  const EstimatedState& est = v.estimator_.state();
  PositionSetpoint& sp = v.sp_;
  // stop at up to the lean limit, then hold where we stopped
  if (!holding_ && est.velocity_enu_m_s.head<2>().norm() < kBrakeHoldSpeedM_S) {
    holding_ = true;
    v.hold_position_enu_m_.head<2>() = est.position_enu_m.head<2>();
  }
  sp.position_enu_m = v.hold_position_enu_m_;
  sp.velocity_enu_m_s.setZero();
  sp.accel_enu_m_s2.setZero();
  sp.use_pos_xy = holding_;
  sp.use_vel_xy = true;
  sp.use_pos_z = true;
  v.control_ = ControlKind::kPosition;
}

// --- LAND
// ------------------------------------------------------------------------------------------

void LandMode::enter(Vehicle& v, bool flying) {
  (void)flying;
  v.land_xy_enu_m_ = v.hold_position_enu_m_;
}

void LandMode::update(Vehicle& v, double dt_s) {
  (void)dt_s;
  v.run_land_descent(v.estimator_.state().gps_ok);
}

// --- RTL
// -------------------------------------------------------------------------------------------

void RtlMode::enter(Vehicle& v, bool flying) {
  if (flying) start(v);
}

void RtlMode::start(Vehicle& v) {
  const EstimatedState& est = v.estimator_.state();
  // climb to RTL_ALT above home if lower, where we are; then fly home at that altitude
  alt_enu_m_ = std::max(est.position_enu_m.z(), v.home_enu_m_.z() + v.params_.derived().rtl_alt_m);
  stage_ = Stage::kClimb;
  v.nav_active_ = false;
  Eigen::Vector3d climb = v.stopping_point();
  climb.z() = alt_enu_m_;
  v.start_nav_to(climb);
}

void RtlMode::update(Vehicle& v, double dt_s) {
  const EstimatedState& est = v.estimator_.state();
  const DerivedParams& d = v.params_.derived();
  NavLimits lim = v.nav_limits();
  switch (stage_) {
    case Stage::kClimb:
      v.run_nav(dt_s, lim);
      if (v.nav_.arrived()) {
        stage_ = Stage::kReturn;
        v.start_nav_to(Eigen::Vector3d(v.home_enu_m_.x(), v.home_enu_m_.y(), alt_enu_m_));
      }
      break;
    case Stage::kReturn:
      lim.speed_xy_m_s = d.rtl_speed_m_s;
      v.run_nav(dt_s, lim);
      if (v.nav_.arrived() &&
          (est.position_enu_m.head<2>() - v.home_enu_m_.head<2>()).norm() < d.wp_radius_m) {
        stage_ = Stage::kLoiter;
        loiter_start_s_ = v.now();
      }
      break;
    case Stage::kLoiter:
      v.run_nav(dt_s, lim);
      if (v.now() - loiter_start_s_ >= d.rtl_loit_time_s) {
        stage_ = Stage::kLand;
        v.land_xy_enu_m_ = Eigen::Vector3d(v.home_enu_m_.x(), v.home_enu_m_.y(), 0.0);
      }
      break;
    case Stage::kLand:
      v.run_land_descent(est.gps_ok);
      break;
  }
}

// --- AUTO
// ------------------------------------------------------------------------------------------

void AutoMode::enter(Vehicle& v, bool flying) {
  (void)flying;
  start_item(v, std::clamp(v.mission_current_, 1, static_cast<int>(v.mission_.size()) - 1));
}

void AutoMode::start_item(Vehicle& v, int seq) {
  const EstimatedState& est = v.estimator_.state();
  v.mission_current_ = seq;
  const int size = static_cast<int>(v.mission_.size());
  if (seq >= size || (v.mission_last_ > 0 && seq > v.mission_last_)) {
    // end of mission: stay in AUTO and hold (ArduCopter MIS_DONE_BEHAVE = 0)
    v.mission_current_ = std::min(seq, size - 1);
    phase_ = Phase::kDone;
    if (v.armed_ && !v.landed_) v.start_hold();
    v.status(6, "Mission complete");
    return;
  }
  const MissionItem& item = v.mission_[static_cast<std::size_t>(seq)];
  phase_ = Phase::kNav;
  switch (item.kind) {
    case MissionItem::Kind::kTakeoff: {
      const double base_z = v.home_set_ ? v.home_enu_m_.z() : est.position_enu_m.z();
      const double target_z = base_z + item.position_enu_m.z();
      if (v.landed_ && v.armed_) {
        v.start_takeoff(target_z);
      } else {
        Eigen::Vector3d dest = v.nav_active_ ? v.nav_.destination() : est.position_enu_m;
        dest.z() = std::max(target_z, est.position_enu_m.z());
        v.start_nav_to(dest);
      }
      break;
    }
    case MissionItem::Kind::kWaypoint:
    case MissionItem::Kind::kLoiterTime:
      v.start_nav_to(item.position_valid ? item.position_enu_m : est.position_enu_m);
      break;
    case MissionItem::Kind::kLand:
      if (item.position_valid) {
        v.start_nav_to(Eigen::Vector3d(item.position_enu_m.x(), item.position_enu_m.y(),
                                       est.position_enu_m.z()));
        phase_ = Phase::kLandApproach;
      } else {
        v.land_xy_enu_m_ = v.stopping_point();
        phase_ = Phase::kLandDescend;
      }
      break;
    case MissionItem::Kind::kRtl:
      rtl_.start(v);
      phase_ = Phase::kRtl;
      break;
    case MissionItem::Kind::kChangeSpeed:
      if (item.param_s_or_m_s > 0.0 && std::isfinite(item.param_s_or_m_s)) {
        v.speed_xy_override_m_s_ = item.param_s_or_m_s;
      }
      complete_item(v);
      break;
    case MissionItem::Kind::kConditionYaw:
      v.yaw_target_rad_ = wrap_pi(item.yaw_enu_rad);
      v.yaw_fixed_ = true;
      phase_ = Phase::kYaw;
      break;
  }
}

void AutoMode::complete_item(Vehicle& v) {
  v.reached_.push(v.mission_current_);
  start_item(v, v.mission_current_ + 1);
}

void AutoMode::update(Vehicle& v, double dt_s) {
  const EstimatedState& est = v.estimator_.state();
  const DerivedParams& d = v.params_.derived();
  const MissionItem& item = v.mission_[static_cast<std::size_t>(
      std::clamp(v.mission_current_, 0, static_cast<int>(v.mission_.size()) - 1))];
  switch (phase_) {
    case Phase::kNav: {
      if (item.kind != MissionItem::Kind::kTakeoff) v.face_destination();
      v.run_nav(dt_s, v.nav_limits());
      const bool within =
          v.nav_.arrived() && (est.position_enu_m - v.nav_.destination()).norm() < d.wp_radius_m;
      if (item.kind == MissionItem::Kind::kTakeoff) {
        if (!v.takeoff_active_ && v.nav_.arrived()) complete_item(v);
      } else if (within) {
        if (item.param_s_or_m_s > 0.0) {
          phase_ = Phase::kHold;
          hold_start_s_ = v.now();
        } else {
          complete_item(v);
        }
      }
      break;
    }
    case Phase::kHold:
      v.run_nav(dt_s, v.nav_limits());
      if (v.now() - hold_start_s_ >= item.param_s_or_m_s) complete_item(v);
      break;
    case Phase::kLandApproach:
      v.face_destination();
      v.run_nav(dt_s, v.nav_limits());
      if (v.nav_.arrived() && (est.position_enu_m - v.nav_.destination()).norm() < d.wp_radius_m) {
        v.land_xy_enu_m_ = v.nav_.destination();
        phase_ = Phase::kLandDescend;
      }
      break;
    case Phase::kLandDescend:
      v.run_land_descent(est.gps_ok);
      break;
    case Phase::kRtl:
      rtl_.update(v, dt_s);
      break;
    case Phase::kYaw:
      v.run_nav(dt_s, v.nav_limits());
      if (std::abs(wrap_pi(v.yaw_target_rad_ - v.estimator_.yaw_enu_rad())) < kYawDoneRad)
        complete_item(v);
      break;
    case Phase::kDone:
      v.run_nav(dt_s, v.nav_limits());
      break;
  }
}

}  // namespace uavsim::server::fc
