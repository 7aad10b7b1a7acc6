#include "run_score.hpp"

#include <algorithm>

namespace uavsim::missions::coverage {

RunTally tally_run(const std::vector<VehicleOutcome>& vehicles, const RunInstants& at,
                   double coverage, bool run_went_through) {
  RunTally t;
  t.coverage = coverage;
  // survivors and landings; energy and distance of every vehicle, the dead's too
  for (const VehicleOutcome& v : vehicles) {
    if (!v.dead) {
      ++t.survivors;
      if (v.down) ++t.landed;
    }
    t.energy_total += v.energy_mah;
    t.distance_total += v.distance_m;
  }
  t.failed = static_cast<int>(vehicles.size()) - t.survivors;
  t.success = run_went_through && !vehicles.empty() && coverage >= kFullCoverage &&
              t.survivors > 0 && t.landed == t.survivors;
  // durations from the first take-off, where both ends happened in order
  const bool took_off = at.first_takeoff_s >= 0;
  t.mission_s = took_off && at.last_touchdown_s >= at.first_takeoff_s
                    ? at.last_touchdown_s - at.first_takeoff_s
                    : -1.0;
  t.coverage_s = took_off && at.completed_at_s >= at.first_takeoff_s
                     ? at.completed_at_s - at.first_takeoff_s
                     : -1.0;
  return t;
}

std::vector<CoverageGap> coverage_gaps(const AreaParts& held, double width_y_m,
                                       std::size_t max_gaps) {
  std::vector<CoverageGap> gaps;
  for (int st = 0; st < held.stripe_count(); ++st) {
    // walk the stripe's intervals from y = 0, with a last one at the far edge
    double y = 0.0;
    std::vector<Interval> list = held.stripe(st);
    list.push_back({width_y_m, width_y_m});
    for (const Interval& iv : list) {
      if (iv.start_m - y > kCoverageSlack_m && gaps.size() < max_gaps)
        gaps.push_back({st, y, std::min(iv.start_m, width_y_m)});
      y = std::max(y, iv.end_m);
    }
  }
  return gaps;
}

}  // namespace uavsim::missions::coverage
