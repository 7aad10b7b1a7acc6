// The countable part of a coverage run's score (the thesis's table 4.2 and fig. 4.7) and the gaps
// in the data the survivors hold, from what the launcher saw at the end of the run. Pure, so each
// rule is checked against hand-computed cases; coverage_run.cpp gathers the inputs from the run.
#pragma once

#include <cstddef>
#include <vector>

#include "area_parts.hpp"

namespace uavsim::missions::coverage {

// A run succeeds only with all of the rectangle held (less the rounding of 1e-3).
inline constexpr double kFullCoverage = 1.0 - 1e-3;

// What the launcher knows of one vehicle at the end of a run.
struct VehicleOutcome {
  bool dead = false;  // killed by the failure draw, or crashed
  bool down = false;  // on the ground and disarmed
  double energy_mah = 0.0;
  double distance_m = 0.0;
};

// Instants of the run, sim time in seconds; negative: it never happened.
struct RunInstants {
  double first_takeoff_s = -1.0;
  double last_touchdown_s = -1.0;
  double completed_at_s = -1.0;  // the leader's query found the rectangle covered
};

struct RunTally {
  double coverage = 0.0;  // held by the survivors (and the ground station), 0 to 1
  int survivors = 0, landed = 0, failed = 0;
  double energy_total = 0, distance_total = 0;
  bool success = false;
  double mission_s = -1.0, coverage_s = -1.0;
};

// (the vehicles at the end, the run's instants, the held coverage, whether the run itself went
// through: no launcher failure, not interrupted) => the tally. A dead vehicle is failed and never
// landed. Success: the run went through, vehicles reported, the coverage is full, and at least
// one vehicle survived and every survivor landed. mission_s runs from the first take-off to the
// last touchdown ("from take-off to landing", fig. 4.7 and table 4.2), coverage_s from the first
// take-off to the completed query, before the flight home; -1 where an end is missing or precedes
// the take-off.
RunTally tally_run(const std::vector<VehicleOutcome>& vehicles, const RunInstants& at,
                   double coverage, bool run_went_through);

// A stretch [from_m, to_m) of a stripe that the held data misses.
struct CoverageGap {
  int stripe = 0;
  double from_m = 0.0;
  double to_m = 0.0;
};

// The stretches of [0, width_y_m] missing from the held data's stripes, wider than
// kCoverageSlack_m, stripe by stripe from y = 0; at most max_gaps of them.
std::vector<CoverageGap> coverage_gaps(const AreaParts& held, double width_y_m,
                                       std::size_t max_gaps);

}  // namespace uavsim::missions::coverage
