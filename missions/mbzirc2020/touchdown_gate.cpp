#include "touchdown_gate.hpp"

#include <algorithm>
#include <cmath>

#include "uavsim/client/geodesy.hpp"
#include "uavsim/common/angles.hpp"

namespace uavsim::missions::mbzirc2020 {

using client::wrap_pi;
using common::kPi;

void TouchdownGate::reset() { *this = TouchdownGate(config_); }

bool TouchdownGate::update(double now_s, const Eigen::Vector2d& velocity_enu_m_s, double roll_rad,
                           double pitch_rad, double yaw_enu_rad) {
  const bool first = last_s_ < 0.0;
  const double dt_s = first ? 0.0 : std::max(now_s - last_s_, 0.0);
  last_s_ = now_s;
  // the thrust axis's horizontal part: in the heading's frame (forward, left) it is
  // (-sin(pitch) cos(roll), -sin(roll)) for NED roll and pitch (nose down leans forward, right wing
  // down leans right)
  const Eigen::Vector2d lean_fl(-std::sin(pitch_rad) * std::cos(roll_rad), -std::sin(roll_rad));
  const double c = std::cos(yaw_enu_rad), s = std::sin(yaw_enu_rad);
  const Eigen::Vector2d lean(c * lean_fl.x() - s * lean_fl.y(), s * lean_fl.x() + c * lean_fl.y());
  // exact first-order low-pass for the sample's interval; the first sample starts it
  const double a = first ? 1.0 : 1.0 - std::exp(-dt_s / config_.wind_tau_s);
  lean_enu_ += a * (lean - lean_enu_);

  const double speed_m_s = velocity_enu_m_s.norm();
  if (!paused_) {
    if (paused_total_s_ < config_.max_pause_s && speed_m_s > config_.pause_speed_m_s) {
      paused_ = true;
      calm_since_s_ = -1.0;
    }
    return !paused_;
  }
  paused_total_s_ += dt_s;
  const bool calm = speed_m_s < config_.calm_speed_m_s;
  if (!calm) {
    calm_since_s_ = -1.0;
  } else if (calm_since_s_ < 0.0) {
    calm_since_s_ = now_s;
  }
  if ((calm && now_s - calm_since_s_ >= config_.calm_for_s) ||
      paused_total_s_ >= config_.max_pause_s) {
    paused_ = false;
  }
  return !paused_;
}

std::optional<double> TouchdownGate::skid_yaw_enu_rad(double yaw_enu_rad) const {
  if (lean_enu_.norm() < std::sin(config_.wind_min_tilt_rad)) return std::nullopt;
  const double upwind_rad = std::atan2(lean_enu_.y(), lean_enu_.x());
  // nose or tail into the wind, whichever is the shorter turn
  const double d = wrap_pi(upwind_rad - yaw_enu_rad);
  return wrap_pi(std::abs(d) <= 0.5 * kPi ? upwind_rad : upwind_rad + kPi);
}

}  // namespace uavsim::missions::mbzirc2020
