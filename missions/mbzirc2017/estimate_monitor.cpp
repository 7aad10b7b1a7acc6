#include "estimate_monitor.hpp"

#include <cmath>

namespace uavsim::missions::mbzirc2017 {

EstimateMonitor::EstimateMonitor(const EstimateMonitorParams& params) : params_(params) {}

void EstimateMonitor::add(double time_s, const Eigen::Vector2d& position_enu_m,
                          const Eigen::Vector2d& velocity_enu_m_s) {
  if (!std::isfinite(time_s) || !position_enu_m.allFinite() || !velocity_enu_m_s.allFinite()) {
    return;
  }
  if (have_last_ && !(time_s > last_time_s_)) return;
  const double dt = have_last_ ? time_s - last_time_s_ : 0.0;
  if (have_last_ && dt <= params_.max_gap_s) {
    // the change the velocity does not explain (trapezoid over the interval)
    window_.push_back({time_s, (position_enu_m - last_position_enu_m_) -
                                   0.5 * (velocity_enu_m_s + last_velocity_enu_m_s_) * dt});
  } else {
    window_.clear();
  }
  have_last_ = true;
  last_time_s_ = time_s;
  last_position_enu_m_ = position_enu_m;
  last_velocity_enu_m_s_ = velocity_enu_m_s;
  // the window: pieces that end within window_s of now
  while (!window_.empty() && window_.front().time_s <= time_s - params_.window_s) {
    window_.pop_front();
  }
  unexplained_.setZero();
  for (const Piece& p : window_) unexplained_ += p.excess_m;
  // a step begins when the sum first crosses the threshold; it lasts while above it
  const bool above = unexplained_.norm() > params_.jump_threshold_m;
  if (above && !above_) ++jumps_;
  if (above) last_jump_s_ = time_s;
  above_ = above;
}

bool EstimateMonitor::settling() const {
  return have_last_ && last_time_s_ - last_jump_s_ < params_.settle_s;
}

}  // namespace uavsim::missions::mbzirc2017
