// The rules every mode shares (entering a mode, the idle on the ground, auto-disarm) and the services the
// modes fly with: the carrot (run_nav, start_hold), take-off, the land descent, the pilot's sticks. The
// modes themselves, one object each, are in flight_modes.cpp.
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
// LAND uses LAND_SPEED_HIGH above this height over home (ArduCopter: LAND_ALT_LOW default 10 m)
constexpr double kLandAltLowM = 10.0;


}  // namespace

bool FlightController::Impl::gps_mode(Mode mode) const { return modes_.of(mode).needs_position(); }

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
  modes_.of(mode_).exit(*this);
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
  guided_sub_ = GuidedSub::kHold;
  pilot_flying_xy_ = false;
  hold_position_enu_m_ = stopping_point();
  active_mode().enter(*this, flying);
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

void FlightController::Impl::run_mode(double dt_s) {
  const ParamValues& p = params_.values();
  FlightMode& mode = active_mode();
  // the pilot's yaw stick turns the vehicle at a rate in the modes that read the sticks
  const std::optional<PilotInput> in = pilot();
  if (mode.reads_pilot()) {
    yaw_rate_mode_ = in.has_value();
    yaw_rate_cmd_rad_s_ = in ? -in->yaw * params_.derived().rate_y_max_rad_s : 0.0;  // stick right: clockwise
  }
  // on the ground and not taking off: idle, and auto-disarm after DISARM_DELAY (unless the pilot's
  // throttle takes off)
  if (landed_ && !takeoff_active_ && !pilot_takeoff()) {
    control_ = ControlKind::kIdle;
    nav_active_ = false;
    if (mode.disarms_when_landed()) {
      do_disarm("Disarming motors: landed");
      return;
    }
    if (p.disarm_delay > 0.0 && now() - landed_since_s_ >= p.disarm_delay) {
      do_disarm("Auto disarm: landed");
    }
    return;
  }
  mode.update(*this, dt_s);
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

}  // namespace uavsim::server::fc
