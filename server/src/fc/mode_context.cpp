// The services the flight modes fly with, over the mode context: the carrot (run_nav, start_hold),
// take-off, the land descent, the pilot's sticks as ArduCopter reads them.
#include "fc/mode_context.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "fc/attitude_control.hpp"

namespace uavsim::server::fc {

namespace {

// take-off is complete when the carrot is at altitude and the vehicle within this
constexpr double kTakeoffDoneM = 0.5;
// "face the waypoint" only while it is further than this horizontally (avoids spinning on arrival)
constexpr double kFaceWaypointMinM = 2.0;
// LAND uses LAND_SPEED_HIGH above this height over home (ArduCopter: LAND_ALT_LOW default 10 m)
constexpr double kLandAltLowM = 10.0;
// a stick dead zone like ArduCopter's RCn_DZ
constexpr double kStickDeadzone = 0.05;

// throttle => climb rate (m/s): 0 inside the dead zone around mid stick, PILOT_SPEED_UP/DN at the
// ends
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

void StatusTexts::push(int severity, std::string_view text) {
  FixedText t;
  t.severity = severity;
  const std::size_t n = std::min(text.size(), t.text.size() - 1);
  std::memcpy(t.text.data(), text.data(), n);
  t.text[n] = '\0';
  ring_.push(t);
}

std::optional<PilotInput> fresh_pilot_input(const PilotState& pilot, const ParamValues& p,
                                            double now_s) {
  const double timeout = p.rc_override_time;
  if (!pilot.time_s || timeout == 0.0) return std::nullopt;
  if (timeout > 0.0 && now_s - *pilot.time_s > timeout) return std::nullopt;
  return pilot.input;
}

double ModeContext::yaw_enu_rad() const {
  const Eigen::Vector3d x_enu = estimate().q_enu_body * Eigen::Vector3d::UnitX();
  return std::atan2(x_enu.y(), x_enu.x());
}

// ------------------------------------------------------------------------------------------------
// the carrot

Eigen::Vector3d ModeContext::stopping_point() const {
  // where the vehicle stops braking at WPNAV_ACCEL (horizontal) and WPNAV_ACCEL_Z (vertical)
  const EstimatedState& est = estimate();
  const DerivedParams& d = derived();
  Eigen::Vector3d p = est.position_enu_m;
  const Eigen::Vector2d v = est.velocity_enu_m_s.head<2>();
  p.head<2>() += v * v.norm() / (2.0 * d.wp_accel_m_s2);
  const double vz = est.velocity_enu_m_s.z();
  p.z() += vz * std::abs(vz) / (2.0 * d.wp_accel_z_m_s2);
  return p;
}

NavLimits ModeContext::nav_limits() const {
  const DerivedParams& d = derived();
  const NavState& nav = s_.nav;
  NavLimits lim;
  lim.speed_xy_m_s = nav.speed_xy_override_m_s > 0.0 ? nav.speed_xy_override_m_s : d.wp_speed_m_s;
  lim.speed_up_m_s =
      nav.speed_up_override_m_s > 0.0 ? nav.speed_up_override_m_s : d.wp_speed_up_m_s;
  lim.speed_dn_m_s =
      nav.speed_dn_override_m_s > 0.0 ? nav.speed_dn_override_m_s : d.wp_speed_dn_m_s;
  lim.accel_xy_m_s2 = d.wp_accel_m_s2;
  lim.accel_z_m_s2 = d.wp_accel_z_m_s2;
  return lim;
}

void ModeContext::start_hold() { start_nav_to(stopping_point()); }

void ModeContext::start_nav_to(const Eigen::Vector3d& destination) {
  const EstimatedState& est = estimate();
  NavState& nav = s_.nav;
  if (nav.active) {
    nav.carrot.set_destination(destination);
  } else {
    nav.carrot.start(est.position_enu_m, est.velocity_enu_m_s, destination);
    nav.active = true;
  }
}

void ModeContext::start_takeoff(double target_z_enu_m) {
  const Eigen::Vector3d start = estimate().position_enu_m;
  s_.nav.carrot.start(start, Eigen::Vector3d::Zero(),
                      Eigen::Vector3d(start.x(), start.y(), target_z_enu_m));
  s_.nav.active = true;
  s_.flight.takeoff_active = true;
  s_.flight.landed = false;
  cascade_.restart_for_takeoff();
  status(6, "Takeoff");
}

void ModeContext::face_destination() {
  if (s_.yaw.fixed || params().wp_yaw_behavior == 0.0) return;
  const Eigen::Vector2d d =
      s_.nav.carrot.destination().head<2>() - estimate().position_enu_m.head<2>();
  if (d.norm() > kFaceWaypointMinM) s_.yaw.target_rad = std::atan2(d.y(), d.x());
}

void ModeContext::run_nav(double dt_s, const NavLimits& limits) {
  NavState& nav = s_.nav;
  PositionSetpoint& sp = s_.command.setpoint;
  if (!nav.active) start_hold();
  nav.carrot.update(dt_s, limits, estimate().position_enu_m);
  sp.position_enu_m = nav.carrot.position();
  sp.velocity_enu_m_s = nav.carrot.velocity();
  sp.accel_enu_m_s2 = nav.carrot.accel();
  sp.use_pos_xy = sp.use_pos_z = sp.use_vel_xy = true;
  s_.command.kind = ControlKind::kPosition;
  // take-off ends when the carrot is at altitude and the vehicle close to it
  if (s_.flight.takeoff_active && nav.carrot.arrived() &&
      std::abs(estimate().position_enu_m.z() - nav.carrot.destination().z()) < kTakeoffDoneM) {
    s_.flight.takeoff_active = false;
  }
}

void ModeContext::run_land_descent(bool hold_xy) {
  const EstimatedState& est = estimate();
  const DerivedParams& d = derived();
  PositionSetpoint& sp = s_.command.setpoint;
  const double height = est.position_enu_m.z() - (home().set ? home().position_enu_m.z() : 0.0);
  const double speed = height > kLandAltLowM ? d.land_speed_high_m_s : d.land_speed_m_s;
  sp.position_enu_m = s_.nav.land_xy_enu_m;
  sp.velocity_enu_m_s = Eigen::Vector3d(0.0, 0.0, -speed);
  sp.accel_enu_m_s2.setZero();
  sp.use_pos_xy = hold_xy;
  sp.use_vel_xy = hold_xy;
  sp.use_pos_z = false;
  s_.command.kind = ControlKind::kPosition;
  s_.nav.active = false;
}

// ------------------------------------------------------------------------------------------------
// the pilot's sticks (RC overrides) in STABILIZE, ALT_HOLD and LOITER, as ArduCopter reads them

std::optional<PilotInput> ModeContext::pilot() const {
  return fresh_pilot_input(s_.pilot, params(), now());
}

double ModeContext::pilot_thrust_n(double throttle) const {
  // ArduCopter's throttle curve in STABILIZE: mid stick hovers (MOT_THST_HOVER), full stick is full
  // thrust
  const double hover = cascade_.hover_thrust_n();
  const double max = cascade_.max_thrust_n();
  if (throttle <= 0.5) return hover * throttle / 0.5;
  return hover + (max - hover) * (throttle - 0.5) / 0.5;
}

void ModeContext::run_pilot_lean(const PilotInput& in) {
  // lean angles up to ANGLE_MAX in any direction (ArduCopter's get_pilot_desired_lean_angles)
  const double max = derived().angle_max_rad;
  double roll = in.roll * max;
  double pitch = in.pitch * max;
  const double total = std::hypot(roll, pitch);
  if (total > max) {
    roll *= max / total;
    pitch *= max / total;
  }
  // FLU body: +roll about x lowers the right side, +pitch about y (left) lowers the nose
  s_.command.q_attitude_target = Eigen::AngleAxisd(s_.yaw.cmd_rad, Eigen::Vector3d::UnitZ()) *
                                 Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
                                 Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX());
  s_.nav.active = false;
}

void ModeContext::run_pilot_climb(const PilotInput& in, double dt_s) {
  (void)dt_s;
  // the throttle's climb rate, or hold the altitude where the pilot left it
  PositionSetpoint& sp = s_.command.setpoint;
  const double climb = pilot_climb_rate(in.throttle, derived());
  sp.velocity_enu_m_s.z() = climb;
  sp.accel_enu_m_s2.z() = 0.0;
  if (climb != 0.0) {
    s_.nav.hold_position_enu_m.z() = estimate().position_enu_m.z();
    sp.use_pos_z = false;
  } else {
    sp.position_enu_m.z() = s_.nav.hold_position_enu_m.z();
    sp.use_pos_z = true;
  }
}

bool ModeContext::run_pilot_loiter(const PilotInput& in, double dt_s) {
  const DerivedParams& d = derived();
  const EstimatedState& est = estimate();
  PositionSetpoint& sp = s_.command.setpoint;
  bool& flying_xy = s_.pilot.flying_xy;
  const bool moving = std::abs(in.roll) > kStickDeadzone || std::abs(in.pitch) > kStickDeadzone ||
                      pilot_climb_rate(in.throttle, d) != 0.0;
  if (!moving) {
    // sticks centred after flying: brake to the stopping point and hold there
    if (flying_xy) {
      flying_xy = false;
      start_hold();
    }
    return false;
  }
  if (!flying_xy) {
    sp.velocity_enu_m_s = est.velocity_enu_m_s;
    s_.nav.hold_position_enu_m.z() = est.position_enu_m.z();
  }
  flying_xy = true;
  s_.nav.active = false;
  // the sticks are a horizontal velocity in the vehicle's heading frame, up to WPNAV_SPEED, reached
  // at WPNAV_ACCEL (ArduCopter: LOIT_SPEED, LOIT_ACC_MAX)
  const double yaw = yaw_enu_rad();
  const Eigen::Vector2d forward(std::cos(yaw), std::sin(yaw));
  const Eigen::Vector2d right(std::sin(yaw), -std::cos(yaw));
  const Eigen::Vector2d want = (in.pitch * forward + in.roll * right) * d.wp_speed_m_s;
  Eigen::Vector2d dv = want - sp.velocity_enu_m_s.head<2>();
  const double dv_max = d.wp_accel_m_s2 * dt_s;
  if (dv.norm() > dv_max) dv *= dv_max / dv.norm();
  sp.velocity_enu_m_s.head<2>() += dv;
  sp.accel_enu_m_s2.head<2>() = dv / dt_s;
  sp.position_enu_m.head<2>() = est.position_enu_m.head<2>();
  sp.use_pos_xy = false;
  sp.use_vel_xy = true;
  run_pilot_climb(in, dt_s);
  s_.command.kind = ControlKind::kPosition;
  s_.command.attitude_climb = false;
  return true;
}

}  // namespace uavsim::server::fc
