// Telling a step in the flight controller's own position estimate from the UAV's motion, from its
// telemetry alone (LOCAL_POSITION_NED). A GPS fix that jumps (field GPS: a jump of about 1.5 m
// every few minutes) is blended in by the FC's complementary filter (server/src/fc/estimator.hpp:
// the position is corrected directly, not only through the velocity), so for a second or two the
// reported position moves faster than the reported velocity says, and meanwhile the FC's velocity
// is off by up to ~2 m/s: the velocity loop then flies the vehicle that far from where it is told.
// Over a moving deck, blind in the last metres, that is how issue 36's seed 52 put a propeller in
// the truck's cab. The monitor sums, over a short window, the position change the velocity does not
// explain; above a threshold the estimate is "settling" until it has been quiet for a while.
// Pure: no I/O, no clock (the samples carry the vehicle's time).
#pragma once

#include <Eigen/Core>
#include <deque>

namespace uavsim::missions::mbzirc2017 {

struct EstimateMonitorParams {
  double window_s = 0.5;          // the unexplained displacement is summed over this long
  double jump_threshold_m = 0.6;  // above: a step in the estimate (noise sums to ~0.2 m)
  double settle_s = 2.5;          // quiet this long after the last step: settled again
  double max_gap_s = 0.5;         // samples further apart start a new window (a telemetry gap)
};

// Not thread-safe: one owner (the UAV program's loop).
class EstimateMonitor {
 public:
  explicit EstimateMonitor(const EstimateMonitorParams& params = {});

  // One telemetry sample: the estimate's time (vehicle clock), horizontal position and velocity.
  // Samples not after the previous one are ignored.
  void add(double time_s, const Eigen::Vector2d& position_enu_m,
           const Eigen::Vector2d& velocity_enu_m_s);

  // Whether the estimate stepped within settle_s before the newest sample.
  bool settling() const;
  // The unexplained horizontal displacement over the window ending at the newest sample [m].
  double unexplained_m() const { return unexplained_.norm(); }
  // Steps seen so far (each begins a settling period).
  int jumps() const { return jumps_; }

 private:
  struct Piece {
    double time_s;
    Eigen::Vector2d excess_m;  // position change minus the velocity's account of it
  };
  EstimateMonitorParams params_;
  bool have_last_ = false;
  double last_time_s_ = 0.0;
  Eigen::Vector2d last_position_enu_m_ = Eigen::Vector2d::Zero();
  Eigen::Vector2d last_velocity_enu_m_s_ = Eigen::Vector2d::Zero();
  std::deque<Piece> window_;
  Eigen::Vector2d unexplained_ = Eigen::Vector2d::Zero();
  bool above_ = false;
  double last_jump_s_ = -1e9;
  int jumps_ = 0;
};

}  // namespace uavsim::missions::mbzirc2017
