#include "flocking.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace uavsim::missions::coverage {

double angle_diff(double a_rad, double b_rad) {
  const double g = std::remainder(a_rad - b_rad, 2.0 * kPi);  // O(1), in [-pi, pi]
  return g;
}

double saturate(double v, double s) { return std::min(s, std::max(-s, v)); }

bool direction_obstructed(const Eigen::Vector2d& local_enu_m, double dir_rad,
                          const std::vector<Eigen::Vector2d>& others_enu_m, double ahead_m,
                          double half_width_m) {
  const Eigen::Vector2d dir(std::cos(dir_rad), std::sin(dir_rad));
  const Eigen::Vector2d across(-dir.y(), dir.x());
  for (const Eigen::Vector2d& o : others_enu_m) {
    const Eigen::Vector2d d = o - local_enu_m;
    const double along = d.dot(dir);
    if (along > 0.0 && along < ahead_m && std::abs(d.dot(across)) < half_width_m) return true;
  }
  return false;
}

namespace {

// How far across the line the nearest agent towards the leader is (among those within d_m along
// the heading); infinity when there is none.
double gap_towards_leader(const FlockInputs& in, const Eigen::Vector2d& parallel_dir,
                          const Eigen::Vector2d& ortho_dir, double ortho_diff, double d_m) {
  double gap = std::numeric_limits<double>::infinity();
  for (const Eigen::Vector2d& o : in.others_enu_m) {
    const Eigen::Vector2d d = o - in.local_enu_m;  // from us to the other agent
    const double across = ortho_dir.dot(d);
    if (across * ortho_diff > 0.0 && std::abs(parallel_dir.dot(d)) < d_m)
      gap = std::min(gap, std::abs(across));
  }
  return gap;
}

}  // namespace

FlockOutputs FlockController::step(const FlockInputs& in) {
  const FlockGains& g = gains_;
  FlockOutputs out;
  const double heading = in.leader_heading_rad;
  const Eigen::Vector2d parallel_dir(std::cos(heading), std::sin(heading));
  const Eigen::Vector2d ortho_dir(std::cos(heading + 0.5 * kPi), std::sin(heading + 0.5 * kPi));
  const Eigen::Vector2d diff = in.leader_enu_m - in.local_enu_m;
  const double parallel_diff = parallel_dir.dot(diff);
  const double ortho_diff = ortho_dir.dot(diff);

  // R2 (alignment): turn towards the leader's heading
  out.yaw_rate_rad_s =
      saturate(g.kp_r2 * angle_diff(heading, in.local_heading_rad), g.s_r2_deg_s * kPi / 180.0);

  // R3x (cohesion along the heading): PI on the distance to our projection on the flock line,
  // unless the way there is taken (then the integral is left alone: no wind-up while blocked)
  const double r3x_dir = parallel_diff >= 0.0 ? heading : heading + kPi;
  out.obstructed =
      direction_obstructed(in.local_enu_m, r3x_dir, in.others_enu_m, g.d_r1_m, 0.5 * g.d_r1_m);
  if (!out.obstructed) {
    const double p = g.kp_r3x * parallel_diff;
    const double candidate = integral_m_s_ + g.ki_r3x * parallel_diff * in.dt_s;
    // integrate only while the output is not saturated (anti-windup)
    if (std::abs(p + candidate) < g.s_r3x_m_s) integral_m_s_ = candidate;
    out.parallel_m_s = saturate(p + integral_m_s_, g.s_r3x_m_s);
  }

  // R1 (separation) from the nearest agent, or R3y (cohesion along the line) towards the leader.
  // The thesis writes R3y as kp * (-orthoDiff) in its simulator's axes; in ENU, towards the leader
  // is +orthoDiff along ortho_dir
  const double r3y = saturate(g.kp_r3y * ortho_diff, g.s_r3y_m_s);
  double best = std::numeric_limits<double>::infinity();
  double near_parallel = 0.0, near_ortho = 0.0;
  for (const Eigen::Vector2d& o : in.others_enu_m) {
    const Eigen::Vector2d d = in.local_enu_m - o;  // from the other agent to us
    const double dist = d.norm();
    if (dist < best) {
      best = dist;
      near_parallel = parallel_dir.dot(d);
      near_ortho = ortho_dir.dot(d);
    }
  }
  if (std::isfinite(best) && std::abs(near_ortho) < g.d_r1_m) {
    // sep = c_p * parallel^2 + c_o * (1 - (|ortho| / D_R1)^d_R1), pushing us away across the line
    const double sep = g.c_p_r1 * near_parallel * near_parallel +
                       g.c_o_r1 * (1.0 - std::pow(std::abs(near_ortho) / g.d_r1_m, g.d_r1));
    // sgn(ortho): away from the neighbour across the line (exactly level with it: the + side)
    const double side = near_ortho > 0.0 ? 1.0 : (near_ortho < 0.0 ? -1.0 : 1.0);
    out.ortho_m_s = saturate(sep, g.s_r1_m_s) * side;
    out.separating = true;
    if (g.close_gap && r3y * side > 0.0 &&
        in.leader_velocity_enu_m_s.norm() <= g.close_gap_leader_speed_m_s) {
      // R1 pushes us towards the leader: close on the next agent that way, up to D_R1 from it
      const double room =
          gap_towards_leader(in, parallel_dir, ortho_dir, ortho_diff, g.d_r1_m) - g.d_r1_m;
      const double closing =
          std::min({std::abs(r3y), g.s_close_gap_m_s, g.kp_close_gap * room}) * side;
      if (room > 0.0 && std::abs(closing) > std::abs(out.ortho_m_s)) {
        out.ortho_m_s = closing;
        out.separating = false;
      }
    }
  } else {
    out.ortho_m_s = r3y;
  }

  out.velocity_enu_m_s =
      out.parallel_m_s * parallel_dir + out.ortho_m_s * ortho_dir + in.leader_velocity_enu_m_s;
  return out;
}

}  // namespace uavsim::missions::coverage
