// The scripted demo flight of `uavsim-server --demo` (the README's main job until the missions exist):
// vehicle 0 arms in GUIDED, takes off to 10 m, visits three waypoints, lands and disarms, printing its
// progress in sim time. It drives the flight controller only through Simulation::post, the same command
// path the MAVLink endpoint uses.
#pragma once

#include <ostream>
#include <string>

#include "sim/simulation.hpp"

namespace uavsim::server::app {

struct DemoResult {
  bool success = false;
  int waypoints_reached = 0;
  double flight_time_s = 0.0;
  double max_altitude_m = 0.0;
  double battery_used_mah = 0.0;
  std::string failure;  // why it failed, if it did
};

class DemoFlight {
 public:
  // Prints progress to out unless quiet.
  DemoFlight(std::ostream& out, bool quiet);
  // Flies the script one control step on (the post-control phase of the step schedule). Loop thread
  // only.
  void on_control_step(sim::Simulation& sim);
  bool finished() const { return finished_; }
  const DemoResult& result() const { return result_; }
  void print_summary(std::ostream& out) const;

 private:
  enum class Phase { kWaitGps, kArm, kClimb, kWaypoints, kLanding, kDone };
  void finish(bool success, const std::string& failure);

  std::ostream& out_;
  bool quiet_;
  Phase phase_ = Phase::kWaitGps;
  size_t waypoint_ = 0;
  double next_report_s_ = 0.0;
  double takeoff_time_s_ = 0.0;
  bool finished_ = false;
  DemoResult result_;
};

}  // namespace uavsim::server::app
