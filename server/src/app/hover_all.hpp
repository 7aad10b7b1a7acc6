// `uavsim-server --hover M`: every vehicle arms in GUIDED, takes off to M metres and holds there,
// with no client at all. It is the floor a mission's wall time is measured against (docs/results/
// performance.md): the server stepping the same vehicles, airborne, with nothing but itself to run.
// Like the demo flight it drives the flight controllers only through Simulation::post, the command
// path the MAVLink endpoint uses; a client that commands a vehicle too is not prevented, only not
// expected.
#pragma once

#include <cstddef>
#include <ostream>
#include <vector>

#include "sim/simulation.hpp"

namespace uavsim::server::app {

class HoverAll {
 public:
  // altitude_m: the take-off altitude, already range-checked by the options (0.5 to 1000 m).
  // Prints when every vehicle has reached it unless quiet.
  HoverAll(double altitude_m, std::ostream& out, bool quiet);
  // Sends each vehicle's take-off once its pre-arm checks pass; notes when all are up. Post-control
  // phase of the step schedule, loop thread only.
  void on_control_step(sim::Simulation& sim);

  // a vehicle counts as up within this of the altitude (the climb's overshoot settles inside it)
  static constexpr double kReachedM = 0.5;

 private:
  double altitude_m_;
  std::ostream& out_;
  bool quiet_;
  std::vector<bool> commanded_;  // take-off sent
  std::vector<bool> reached_;    // climbed to within kReachedM of the altitude
  std::size_t reached_count_ = 0;
  bool all_reported_ = false;
};

}  // namespace uavsim::server::app
