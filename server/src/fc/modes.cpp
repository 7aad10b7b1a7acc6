// Mode logic: what each ArduCopter mode asks of the cascade, and AUTO's mission sequencing.
#include <algorithm>
#include <cmath>

#include "fc/angles.hpp"
#include "fc/fc_impl.hpp"
#include "fc/flight_controller.hpp"

namespace uavsim::server::fc {

namespace {

// take-off is complete when the carrot is at altitude and the vehicle within this
constexpr double kTakeoffDoneM = 0.5;
// "face the waypoint" only while it is further than this horizontally (avoids spinning on arrival)
constexpr double kFaceWaypointMinM = 2.0;
// BRAKE latches a position hold below this horizontal speed
constexpr double kBrakeHoldSpeedM_S = 0.2;
// LAND uses LAND_SPEED_HIGH above this height over home (ArduCopter: LAND_ALT_LOW default 10 m)
constexpr double kLandAltLowM = 10.0;
// CONDITION_YAW completes within this heading error
constexpr double kYawDoneRad = 5.0 * kPi / 180.0;
// GUIDED velocity targets: how far the integrated position target may lead the vehicle
constexpr double kGuidedLeashM = 2.0;


}  // namespace

bool FlightController::Impl::gps_mode(Mode mode) const {
  return mode == Mode::kAuto || mode == Mode::kGuided || mode == Mode::kLoiter ||
         mode == Mode::kRtl || mode == Mode::kBrake;
}

Eigen::Vector3d FlightController::Impl::stopping_point() const {
  // where the vehicle stops braking at WPNAV_ACCEL (horizontal) and WPNAV_ACCEL_Z (vertical)
  const EstimatedState& est = estimator_.state();
  const DerivedParams& d = params_.derived();
  Eigen::Vector3d p = est.position_enu_m;
  const Eigen::Vector2d v = est.velocity_enu_m_s.head<2>();
  p.head<2>() += v * v.norm() / (2.0 * d.wp_accel_m_s2);
  const double vz = est.velocity_enu_m_s.z();
  p.z() += vz * std::abs(vz) / (2.0 * d.wp_accel_z_m_s2);
  return p;
}

bool FlightController::Impl::enter_mode(Mode mode, bool from_failsafe) {
  // position modes need a position estimate
  if (gps_mode(mode) && !(estimator_.state().gps_ok && estimator_converged_)) {
    status(4, std::string("Mode change to ") + mode_name(mode) + " failed: requires position");
    return false;
  }
  if (mode == Mode::kAuto && mission_.size() < 2) {
    status(4, "Mode change to AUTO failed: no mission");
    return false;
  }
  mode_ = mode;
  if (!from_failsafe) status(6, std::string("Mode ") + mode_name(mode));
  // a commanded heading, speed changes and a take-off in progress belong to the old mode
  yaw_fixed_ = false;
  yaw_rate_mode_ = false;
  yaw_slew_override_rad_s_ = 0.0;
  speed_xy_override_m_s_ = 0.0;
  speed_up_override_m_s_ = 0.0;
  speed_dn_override_m_s_ = 0.0;
  if (armed_) init_mode_state();
  return true;
}

void FlightController::Impl::init_mode_state() {
  const bool flying = armed_ && !landed_;
  // a GUIDED take-off ends with any change to another mode (LAND during the climb must be able to
  // detect its landing); AUTO's take-off items start their own
  if (mode_ != Mode::kGuided) takeoff_active_ = false;
  nav_active_ = false;
  attitude_climb_ = false;
  brake_holding_ = false;
  guided_sub_ = GuidedSub::kHold;
  pilot_flying_xy_ = false;
  hold_position_enu_m_ = stopping_point();
  switch (mode_) {
    case Mode::kStabilize:
      // no pilot: hold level with the collective we had (idle on the ground)
      fixed_thrust_n_ = flying ? mixer_status_.thrust_n : 0.0;
      break;
    case Mode::kAltHold:
    case Mode::kBrake:
      break;
    case Mode::kGuided:
    case Mode::kLoiter:
      if (flying) start_hold();
      break;
    case Mode::kLand:
      land_xy_enu_m_ = hold_position_enu_m_;
      break;
    case Mode::kRtl:
      if (flying) start_rtl();
      break;
    case Mode::kAuto:
      start_mission_item(std::clamp(mission_current_, 1, static_cast<int>(mission_.size()) - 1));
      break;
  }
}

void FlightController::Impl::start_hold() {
  start_nav_to(stopping_point());
}

void FlightController::Impl::start_nav_to(const Eigen::Vector3d& destination) {
  const EstimatedState& est = estimator_.state();
  if (nav_active_) {
    nav_.set_destination(destination);
  } else {
    nav_.start(est.position_enu_m, est.velocity_enu_m_s, destination);
    nav_active_ = true;
  }
}

void FlightController::Impl::start_takeoff(double target_z_enu_m) {
  const EstimatedState& est = estimator_.state();
  Eigen::Vector3d start = est.position_enu_m;
  nav_.start(start, Eigen::Vector3d::Zero(), Eigen::Vector3d(start.x(), start.y(), target_z_enu_m));
  nav_active_ = true;
  takeoff_active_ = true;
  landed_ = false;
  land_detect_s_ = 0.0;
  pos_ctrl_.reset();
  att_ctrl_.reset();
  status(6, "Takeoff");
}

void FlightController::Impl::face_destination() {
  if (yaw_fixed_ || params_.values().wp_yaw_behavior == 0.0) return;
  const Eigen::Vector2d d =
      nav_.destination().head<2>() - estimator_.state().position_enu_m.head<2>();
  if (d.norm() > kFaceWaypointMinM) yaw_target_rad_ = std::atan2(d.y(), d.x());
}

void FlightController::Impl::run_nav(double dt_s, const NavLimits& limits) {
  if (!nav_active_) start_hold();
  nav_.update(dt_s, limits, estimator_.state().position_enu_m);
  sp_.position_enu_m = nav_.position();
  sp_.velocity_enu_m_s = nav_.velocity();
  sp_.accel_enu_m_s2 = nav_.accel();
  sp_.use_pos_xy = sp_.use_pos_z = sp_.use_vel_xy = true;
  control_ = ControlKind::kPosition;
  // take-off ends when the carrot is at altitude and the vehicle close to it
  if (takeoff_active_ && nav_.arrived() &&
      std::abs(estimator_.state().position_enu_m.z() - nav_.destination().z()) < kTakeoffDoneM) {
    takeoff_active_ = false;
  }
}

void FlightController::Impl::run_land_descent(bool hold_xy) {
  const EstimatedState& est = estimator_.state();
  const DerivedParams& d = params_.derived();
  const double height = est.position_enu_m.z() - (home_set_ ? home_enu_m_.z() : 0.0);
  const double speed = height > kLandAltLowM ? d.land_speed_high_m_s : d.land_speed_m_s;
  sp_.position_enu_m = land_xy_enu_m_;
  sp_.velocity_enu_m_s = Eigen::Vector3d(0.0, 0.0, -speed);
  sp_.accel_enu_m_s2.setZero();
  sp_.use_pos_xy = hold_xy;
  sp_.use_vel_xy = hold_xy;
  sp_.use_pos_z = false;
  control_ = ControlKind::kPosition;
  nav_active_ = false;
}

void FlightController::Impl::start_rtl() {
  const EstimatedState& est = estimator_.state();
  // climb to RTL_ALT above home if lower, where we are; then fly home at that altitude
  rtl_alt_enu_m_ = std::max(est.position_enu_m.z(), home_enu_m_.z() + params_.derived().rtl_alt_m);
  rtl_state_ = RtlState::kClimb;
  nav_active_ = false;
  Eigen::Vector3d climb = stopping_point();
  climb.z() = rtl_alt_enu_m_;
  start_nav_to(climb);
}

void FlightController::Impl::run_rtl(double dt_s) {
  const EstimatedState& est = estimator_.state();
  const DerivedParams& d = params_.derived();
  NavLimits lim = nav_limits();
  switch (rtl_state_) {
    case RtlState::kClimb:
      run_nav(dt_s, lim);
      if (nav_.arrived()) {
        rtl_state_ = RtlState::kReturn;
        start_nav_to(Eigen::Vector3d(home_enu_m_.x(), home_enu_m_.y(), rtl_alt_enu_m_));
      }
      break;
    case RtlState::kReturn:
      lim.speed_xy_m_s = d.rtl_speed_m_s;
      run_nav(dt_s, lim);
      if (nav_.arrived() &&
          (est.position_enu_m.head<2>() - home_enu_m_.head<2>()).norm() < d.wp_radius_m) {
        rtl_state_ = RtlState::kLoiter;
        rtl_loiter_start_s_ = now();
      }
      break;
    case RtlState::kLoiter:
      run_nav(dt_s, lim);
      if (now() - rtl_loiter_start_s_ >= d.rtl_loit_time_s) {
        rtl_state_ = RtlState::kLand;
        land_xy_enu_m_ = Eigen::Vector3d(home_enu_m_.x(), home_enu_m_.y(), 0.0);
      }
      break;
    case RtlState::kLand:
      run_land_descent(est.gps_ok);
      break;
  }
}

void FlightController::Impl::run_mode(double dt_s) {
  const EstimatedState& est = estimator_.state();
  const ParamValues& p = params_.values();
  // the pilot's yaw stick turns the vehicle at a rate in the modes that read the sticks
  const std::optional<PilotInput> in = pilot();
  if (mode_ == Mode::kStabilize || mode_ == Mode::kAltHold || mode_ == Mode::kLoiter) {
    yaw_rate_mode_ = in.has_value();
    yaw_rate_cmd_rad_s_ = in ? -in->yaw * params_.derived().rate_y_max_rad_s : 0.0;  // stick right: clockwise
  }
  // on the ground and not taking off: idle, and auto-disarm after DISARM_DELAY (unless the pilot's
  // throttle takes off)
  if (landed_ && !takeoff_active_ && !pilot_takeoff()) {
    control_ = ControlKind::kIdle;
    nav_active_ = false;
    if (mode_ == Mode::kLand || mode_ == Mode::kRtl) {
      do_disarm("Disarming motors: landed");
      return;
    }
    if (p.disarm_delay > 0.0 && now() - landed_since_s_ >= p.disarm_delay) {
      do_disarm("Auto disarm: landed");
    }
    return;
  }
  switch (mode_) {
    case Mode::kStabilize: {
      control_ = ControlKind::kAttitude;
      attitude_climb_ = false;
      if (in) {
        // the sticks lean the vehicle; the throttle is the collective
        run_pilot_lean(*in);
        fixed_thrust_n_ = pilot_thrust_n(in->throttle);
      } else {
        q_attitude_target_ = attitude_from_thrust(Eigen::Vector3d::UnitZ(), yaw_cmd_rad_, 0.0);
      }
      break;
    }
    case Mode::kAltHold: {
      if (takeoff_active_) {
        run_nav(dt_s, nav_limits());
        hold_position_enu_m_ = nav_.destination();
        break;
      }
      if (in) {
        // the sticks lean the vehicle; the throttle is a climb rate
        run_pilot_lean(*in);
        run_pilot_climb(*in, dt_s);
        sp_.use_pos_xy = false;
        sp_.use_vel_xy = false;
        control_ = ControlKind::kAttitude;
        attitude_climb_ = true;
        break;
      }
      // hold altitude; no horizontal control: level attitude
      sp_.position_enu_m = hold_position_enu_m_;
      sp_.velocity_enu_m_s.setZero();
      sp_.accel_enu_m_s2.setZero();
      sp_.use_pos_xy = false;
      sp_.use_vel_xy = false;
      sp_.use_pos_z = true;
      control_ = ControlKind::kPosition;
      break;
    }
    case Mode::kGuided:
      run_guided(dt_s);
      break;
    case Mode::kLoiter:
      if (in && run_pilot_loiter(*in, dt_s)) break;
      run_nav(dt_s, nav_limits());
      break;
    case Mode::kBrake: {
      // stop at up to the lean limit, then hold where we stopped
      if (!brake_holding_ && est.velocity_enu_m_s.head<2>().norm() < kBrakeHoldSpeedM_S) {
        brake_holding_ = true;
        hold_position_enu_m_.head<2>() = est.position_enu_m.head<2>();
      }
      sp_.position_enu_m = hold_position_enu_m_;
      sp_.velocity_enu_m_s.setZero();
      sp_.accel_enu_m_s2.setZero();
      sp_.use_pos_xy = brake_holding_;
      sp_.use_vel_xy = true;
      sp_.use_pos_z = true;
      control_ = ControlKind::kPosition;
      break;
    }
    case Mode::kLand:
      run_land_descent(est.gps_ok);
      break;
    case Mode::kRtl:
      run_rtl(dt_s);
      break;
    case Mode::kAuto:
      run_auto(dt_s);
      break;
  }
}

// ---------------------------------------------------------------------------------------------------
// the pilot's sticks (RC overrides) in STABILIZE, ALT_HOLD and LOITER, as ArduCopter reads them

namespace {
// ArduCopter's THR_DZ (100 of the 1000 us throttle range) and a stick dead zone like its RCn_DZ
constexpr double kThrottleDeadzone = 0.1;
constexpr double kStickDeadzone = 0.05;

// throttle => climb rate (m/s): 0 inside the dead zone around mid stick, PILOT_SPEED_UP/DN at the ends
double pilot_climb_rate(double throttle, const DerivedParams& d) {
  if (throttle > 0.5 + kThrottleDeadzone) {
    return (throttle - 0.5 - kThrottleDeadzone) / (0.5 - kThrottleDeadzone) * d.pilot_speed_up_m_s;
  }
  if (throttle < 0.5 - kThrottleDeadzone) {
    return (throttle - 0.5 + kThrottleDeadzone) / (0.5 - kThrottleDeadzone) * d.pilot_speed_dn_m_s;
  }
  return 0.0;
}
}  // namespace

bool FlightController::Impl::pilot_takeoff() {
  const std::optional<PilotInput> in = pilot();
  if (!armed_ || !in || in->throttle <= 0.5 + kThrottleDeadzone) return false;
  if (mode_ == Mode::kLoiter && !estimator_.position_ok()) return false;
  landed_ = false;
  land_detect_s_ = 0.0;
  pos_ctrl_.reset();
  att_ctrl_.reset();
  hold_position_enu_m_ = estimator_.state().position_enu_m;
  sp_.position_enu_m = hold_position_enu_m_;
  sp_.velocity_enu_m_s.setZero();
  pilot_flying_xy_ = false;
  status(6, "Takeoff");
  return true;
}

double FlightController::Impl::pilot_thrust_n(double throttle) const {
  // ArduCopter's throttle curve in STABILIZE: mid stick hovers (MOT_THST_HOVER), full stick is full thrust
  const double max = active_mixer().max_total_thrust_n();
  if (throttle <= 0.5) return hover_thrust_n_ * throttle / 0.5;
  return hover_thrust_n_ + (max - hover_thrust_n_) * (throttle - 0.5) / 0.5;
}

void FlightController::Impl::run_pilot_lean(const PilotInput& in) {
  // lean angles up to ANGLE_MAX in any direction (ArduCopter's get_pilot_desired_lean_angles)
  const double max = params_.derived().angle_max_rad;
  double roll = in.roll * max;
  double pitch = in.pitch * max;
  const double total = std::hypot(roll, pitch);
  if (total > max) {
    roll *= max / total;
    pitch *= max / total;
  }
  // FLU body: +roll about x lowers the right side, +pitch about y (left) lowers the nose
  q_attitude_target_ = Eigen::AngleAxisd(yaw_cmd_rad_, Eigen::Vector3d::UnitZ()) *
                       Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
                       Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX());
  nav_active_ = false;
}

void FlightController::Impl::run_pilot_climb(const PilotInput& in, double dt_s) {
  (void)dt_s;
  // the throttle's climb rate, or hold the altitude where the pilot left it
  const double climb = pilot_climb_rate(in.throttle, params_.derived());
  sp_.velocity_enu_m_s.z() = climb;
  sp_.accel_enu_m_s2.z() = 0.0;
  if (climb != 0.0) {
    hold_position_enu_m_.z() = estimator_.state().position_enu_m.z();
    sp_.use_pos_z = false;
  } else {
    sp_.position_enu_m.z() = hold_position_enu_m_.z();
    sp_.use_pos_z = true;
  }
}

bool FlightController::Impl::run_pilot_loiter(const PilotInput& in, double dt_s) {
  const DerivedParams& d = params_.derived();
  const EstimatedState& est = estimator_.state();
  const bool moving = std::abs(in.roll) > kStickDeadzone || std::abs(in.pitch) > kStickDeadzone ||
                      pilot_climb_rate(in.throttle, d) != 0.0;
  if (!moving) {
    // sticks centred after flying: brake to the stopping point and hold there
    if (pilot_flying_xy_) {
      pilot_flying_xy_ = false;
      start_hold();
    }
    return false;
  }
  if (!pilot_flying_xy_) {
    sp_.velocity_enu_m_s = est.velocity_enu_m_s;
    hold_position_enu_m_.z() = est.position_enu_m.z();
  }
  pilot_flying_xy_ = true;
  nav_active_ = false;
  // the sticks are a horizontal velocity in the vehicle's heading frame, up to WPNAV_SPEED, reached at
  // WPNAV_ACCEL (ArduCopter: LOIT_SPEED, LOIT_ACC_MAX)
  const double yaw = estimator_.yaw_enu_rad();
  const Eigen::Vector2d forward(std::cos(yaw), std::sin(yaw));
  const Eigen::Vector2d right(std::sin(yaw), -std::cos(yaw));
  const Eigen::Vector2d want = (in.pitch * forward + in.roll * right) * d.wp_speed_m_s;
  Eigen::Vector2d dv = want - sp_.velocity_enu_m_s.head<2>();
  const double dv_max = d.wp_accel_m_s2 * dt_s;
  if (dv.norm() > dv_max) dv *= dv_max / dv.norm();
  sp_.velocity_enu_m_s.head<2>() += dv;
  sp_.accel_enu_m_s2.head<2>() = dv / dt_s;
  sp_.position_enu_m.head<2>() = est.position_enu_m.head<2>();
  sp_.use_pos_xy = false;
  sp_.use_vel_xy = true;
  run_pilot_climb(in, dt_s);
  control_ = ControlKind::kPosition;
  attitude_climb_ = false;
  return true;
}

void FlightController::Impl::run_guided(double dt_s) {
  const EstimatedState& est = estimator_.state();
  const ParamValues& p = params_.values();
  const DerivedParams& d = params_.derived();
  const double since_cmd = now() - guided_cmd_time_s_;
  const GuidedTarget& t = guided_target_;
  const bool is_new = guided_new_;
  const bool reinit = guided_reinit_;
  guided_new_ = false;
  guided_reinit_ = false;
  switch (guided_sub_) {
    case GuidedSub::kHold:
    case GuidedSub::kTakeoff:
      run_nav(dt_s, nav_limits());
      if (guided_sub_ == GuidedSub::kTakeoff && !takeoff_active_) guided_sub_ = GuidedSub::kWp;
      break;
    case GuidedSub::kWp:
      face_destination();
      run_nav(dt_s, nav_limits());
      break;
    case GuidedSub::kPosVelAccel: {
      // the position target moves with the commanded velocity; velocity and accel time out
      const bool fresh = since_cmd < p.guid_timeout;
      if (is_new) sp_.position_enu_m = *t.position_enu_m;
      sp_.velocity_enu_m_s = fresh && t.velocity_enu_m_s ? *t.velocity_enu_m_s : Eigen::Vector3d::Zero();
      sp_.accel_enu_m_s2 = fresh && t.accel_enu_m_s2 ? *t.accel_enu_m_s2 : Eigen::Vector3d::Zero();
      sp_.position_enu_m += sp_.velocity_enu_m_s * dt_s;
      sp_.use_pos_xy = sp_.use_pos_z = sp_.use_vel_xy = true;
      control_ = ControlKind::kPosition;
      break;
    }
    case GuidedSub::kVelAccel:
    case GuidedSub::kAccel: {
      if (since_cmd >= p.guid_timeout) {
        // ArduCopter: velocity/accel targets stop after GUID_TIMEOUT; then hold
        guided_sub_ = GuidedSub::kHold;
        nav_active_ = false;
        start_hold();
        run_nav(dt_s, nav_limits());
        break;
      }
      if (reinit) {
        sp_.position_enu_m = est.position_enu_m;
        sp_.velocity_enu_m_s = est.velocity_enu_m_s;
      }
      nav_active_ = false;
      // shape the velocity target with WPNAV_ACCEL / WPNAV_ACCEL_Z so the integrated position target
      // does not run away from the vehicle (ArduCopter's input shaping)
      Eigen::Vector3d vel_cmd;
      if (guided_sub_ == GuidedSub::kVelAccel) {
        vel_cmd = *t.velocity_enu_m_s;
        sp_.accel_enu_m_s2 = t.accel_enu_m_s2 ? *t.accel_enu_m_s2 : Eigen::Vector3d::Zero();
      } else {
        sp_.accel_enu_m_s2 = *t.accel_enu_m_s2;
        vel_cmd = sp_.velocity_enu_m_s + sp_.accel_enu_m_s2 * dt_s;
      }
      Eigen::Vector3d dv = vel_cmd - sp_.velocity_enu_m_s;
      const double dv_xy = dv.head<2>().norm(), dv_xy_max = d.wp_accel_m_s2 * dt_s;
      if (dv_xy > dv_xy_max) dv.head<2>() *= dv_xy_max / dv_xy;
      dv.z() = std::clamp(dv.z(), -d.wp_accel_z_m_s2 * dt_s, d.wp_accel_z_m_s2 * dt_s);
      sp_.velocity_enu_m_s += dv;
      if (guided_sub_ == GuidedSub::kVelAccel && !t.accel_enu_m_s2) sp_.accel_enu_m_s2 = dv / dt_s;
      // the position target integrates the velocity, kept within a leash of the vehicle
      sp_.position_enu_m += sp_.velocity_enu_m_s * dt_s;
      Eigen::Vector3d lead = sp_.position_enu_m - est.position_enu_m;
      if (lead.norm() > kGuidedLeashM) {
        sp_.position_enu_m = est.position_enu_m + lead * (kGuidedLeashM / lead.norm());
      }
      sp_.use_pos_xy = sp_.use_pos_z = sp_.use_vel_xy = true;
      control_ = ControlKind::kPosition;
      break;
    }
    case GuidedSub::kAttitude: {
      const AttitudeTarget& a = attitude_target_;
      const bool fresh = since_cmd < p.guid_timeout;
      // thrust 0.5 = hold climb rate 0; above/below scale to PILOT_SPEED_UP/DN (ArduCopter)
      const double thrust = fresh ? a.thrust : 0.5;
      const double climb = thrust >= 0.5 ? (thrust - 0.5) * 2.0 * d.pilot_speed_up_m_s
                                         : (thrust - 0.5) * 2.0 * d.pilot_speed_dn_m_s;
      sp_.velocity_enu_m_s = Eigen::Vector3d(0.0, 0.0, climb);
      sp_.accel_enu_m_s2.setZero();
      sp_.use_pos_xy = sp_.use_pos_z = sp_.use_vel_xy = false;
      attitude_climb_ = true;
      nav_active_ = false;
      if (fresh && !a.q_enu_body && a.rate_body_rad_s) {
        control_ = ControlKind::kBodyRate;
        rate_target_body_rad_s_ = *a.rate_body_rad_s;
        break;
      }
      control_ = ControlKind::kAttitude;
      if (fresh && a.q_enu_body) {
        // keep the commanded heading; limit the lean to ANGLE_MAX
        const Eigen::Vector3d x_enu = *a.q_enu_body * Eigen::Vector3d::UnitX();
        const Eigen::Vector3d z_enu = *a.q_enu_body * Eigen::Vector3d::UnitZ();
        yaw_target_rad_ = std::atan2(x_enu.y(), x_enu.x());
        yaw_cmd_rad_ = yaw_target_rad_;
        q_attitude_target_ = attitude_from_thrust(z_enu, yaw_target_rad_, d.angle_max_rad);
      } else {
        q_attitude_target_ = attitude_from_thrust(Eigen::Vector3d::UnitZ(), yaw_cmd_rad_, 0.0);
      }
      break;
    }
  }
}

void FlightController::Impl::start_mission_item(int seq) {
  const EstimatedState& est = estimator_.state();
  mission_current_ = seq;
  const int size = static_cast<int>(mission_.size());
  if (seq >= size || (mission_last_ > 0 && seq > mission_last_)) {
    // end of mission: stay in AUTO and hold (ArduCopter MIS_DONE_BEHAVE = 0)
    mission_current_ = std::min(seq, size - 1);
    auto_phase_ = AutoPhase::kDone;
    if (armed_ && !landed_) start_hold();
    status(6, "Mission complete");
    return;
  }
  const MissionItem& item = mission_[static_cast<std::size_t>(seq)];
  auto_phase_ = AutoPhase::kNav;
  switch (item.kind) {
    case MissionItem::Kind::kTakeoff: {
      const double base_z = home_set_ ? home_enu_m_.z() : est.position_enu_m.z();
      const double target_z = base_z + item.position_enu_m.z();
      if (landed_ && armed_) {
        start_takeoff(target_z);
      } else {
        Eigen::Vector3d dest = nav_active_ ? nav_.destination() : est.position_enu_m;
        dest.z() = std::max(target_z, est.position_enu_m.z());
        start_nav_to(dest);
      }
      break;
    }
    case MissionItem::Kind::kWaypoint:
    case MissionItem::Kind::kLoiterTime:
      start_nav_to(item.position_valid ? item.position_enu_m : est.position_enu_m);
      break;
    case MissionItem::Kind::kLand:
      if (item.position_valid) {
        start_nav_to(Eigen::Vector3d(item.position_enu_m.x(), item.position_enu_m.y(),
                                     est.position_enu_m.z()));
        auto_phase_ = AutoPhase::kLandApproach;
      } else {
        land_xy_enu_m_ = stopping_point();
        auto_phase_ = AutoPhase::kLandDescend;
      }
      break;
    case MissionItem::Kind::kRtl:
      start_rtl();
      auto_phase_ = AutoPhase::kRtl;
      break;
    case MissionItem::Kind::kChangeSpeed:
      if (item.param_s_or_m_s > 0.0 && std::isfinite(item.param_s_or_m_s)) {
        speed_xy_override_m_s_ = item.param_s_or_m_s;
      }
      complete_mission_item();
      break;
    case MissionItem::Kind::kConditionYaw:
      yaw_target_rad_ = wrap_pi(item.yaw_enu_rad);
      yaw_fixed_ = true;
      auto_phase_ = AutoPhase::kYaw;
      break;
  }
}

void FlightController::Impl::complete_mission_item() {
  reached_.push(mission_current_);
  start_mission_item(mission_current_ + 1);
}

void FlightController::Impl::run_auto(double dt_s) {
  const EstimatedState& est = estimator_.state();
  const DerivedParams& d = params_.derived();
  const MissionItem& item = mission_[static_cast<std::size_t>(
      std::clamp(mission_current_, 0, static_cast<int>(mission_.size()) - 1))];
  switch (auto_phase_) {
    case AutoPhase::kNav: {
      if (item.kind != MissionItem::Kind::kTakeoff) face_destination();
      run_nav(dt_s, nav_limits());
      const bool within =
          nav_.arrived() && (est.position_enu_m - nav_.destination()).norm() < d.wp_radius_m;
      if (item.kind == MissionItem::Kind::kTakeoff) {
        if (!takeoff_active_ && nav_.arrived()) complete_mission_item();
      } else if (within) {
        if (item.param_s_or_m_s > 0.0) {
          auto_phase_ = AutoPhase::kHold;
          auto_hold_start_s_ = now();
        } else {
          complete_mission_item();
        }
      }
      break;
    }
    case AutoPhase::kHold:
      run_nav(dt_s, nav_limits());
      if (now() - auto_hold_start_s_ >= item.param_s_or_m_s) complete_mission_item();
      break;
    case AutoPhase::kLandApproach:
      face_destination();
      run_nav(dt_s, nav_limits());
      if (nav_.arrived() && (est.position_enu_m - nav_.destination()).norm() < d.wp_radius_m) {
        land_xy_enu_m_ = nav_.destination();
        auto_phase_ = AutoPhase::kLandDescend;
      }
      break;
    case AutoPhase::kLandDescend:
      run_land_descent(est.gps_ok);
      break;
    case AutoPhase::kRtl:
      run_rtl(dt_s);
      break;
    case AutoPhase::kYaw:
      run_nav(dt_s, nav_limits());
      if (std::abs(wrap_pi(yaw_target_rad_ - estimator_.yaw_enu_rad())) < kYawDoneRad) {
        complete_mission_item();
      }
      break;
    case AutoPhase::kDone:
      run_nav(dt_s, nav_limits());
      break;
  }
}

}  // namespace uavsim::server::fc
