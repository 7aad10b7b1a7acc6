// The flocking rules of a non-leader agent (the thesis the project descends from, section 3.2 and
// Algorithm 3), with the gains of table 4.1 (FlockGains). The flock line is the leader's local y
// axis; a follower
//   R1  (separation) moves away from its nearest neighbour along the flock line when closer than
//       D_R1 across it,
//   R2  (alignment) turns to the leader's heading,
//   R3x (cohesion along the heading) moves onto the flock line with a PI controller unless another
//       agent is in the way,
//   R3y (cohesion along the line) moves towards the leader when R1 is idle; beyond the thesis
//       (FlockGains::close_gap), where R1 pushes towards the leader, the follower also closes on
//       the next agent that way, up to D_R1 from it.
// Pure: the caller passes the ADB's view of the others and the control period.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "coverage_config.hpp"

namespace uavsim::missions::coverage {

// ANGDIFF(a, b): a - b wrapped into [-pi, pi].
double angle_diff(double a_rad, double b_rad);
// SATURATE(v, s): v clamped to [-s, s].
double saturate(double v, double s);

struct FlockInputs {
  Eigen::Vector2d local_enu_m = Eigen::Vector2d::Zero();
  double local_heading_rad = 0.0;
  Eigen::Vector2d leader_enu_m = Eigen::Vector2d::Zero();
  double leader_heading_rad = 0.0;  // the target heading (R2) and the flock line's orientation
  // the leader's velocity, added as feed-forward so that followers keep up with a leader moving
  // faster than s_R3x (the thesis's followers only close the gap with the PI); zero to disable
  Eigen::Vector2d leader_velocity_enu_m_s = Eigen::Vector2d::Zero();
  std::vector<Eigen::Vector2d> others_enu_m;  // every other agent in the ADB, the leader included
  double dt_s = 0.05;
};

struct FlockOutputs {
  Eigen::Vector2d velocity_enu_m_s = Eigen::Vector2d::Zero();
  double yaw_rate_rad_s = 0.0;  // R2
  double parallel_m_s = 0.0;    // R3x (along the heading)
  double ortho_m_s = 0.0;       // R1 or R3y (along the flock line)
  bool separating = false;      // R1 applied (else R3y)
  bool obstructed = false;      // R3x's direction blocked
};

class FlockController {
 public:
  explicit FlockController(const FlockGains& gains) : gains_(gains) {}

  // One control period of Algorithm 3 (CONTROLLER_NONLEADER).
  FlockOutputs step(const FlockInputs& in);
  void reset() { integral_m_s_ = 0.0; }

 private:
  FlockGains gains_;
  double integral_m_s_ = 0.0;  // R3x's integral term (k_I * sum(diff * dt))
};

// ISDIRECTIONOBSTRUCTED: another agent lies ahead in direction dir_rad, closer than `ahead_m` along
// it and within `half_width_m` across it.
bool direction_obstructed(const Eigen::Vector2d& local_enu_m, double dir_rad,
                          const std::vector<Eigen::Vector2d>& others_enu_m, double ahead_m,
                          double half_width_m);

}  // namespace uavsim::missions::coverage
