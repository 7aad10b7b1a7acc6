// The leader's path planning (the thesis the project descends from, section 3.5): from the
// aggregated coverage map it builds two candidate paths along x, on the low-y and the high-y
// frontier of the covered area (the thesis's left and right frontier), keeps the one whose start is
// nearer the flock, removes control points that would swing the flock sideways too far (threshold)
// and smooths the rest (moving average). The path is the leader's own track: it is translated so
// that the flock's edge (estimated from the leader's ADB) lies on the frontier, overlapping it by a
// margin. Pure.
#pragma once

#include <Eigen/Core>
#include <optional>
#include <vector>

#include "area_parts.hpp"
#include "coverage_config.hpp"

namespace uavsim::missions::coverage {

// Where the leader sits in the flock line, along y: the flock's lowest agent is low_extent_m below
// the leader, its highest high_extent_m above.
struct FlockExtent {
  double low_extent_m = 0.0;
  double high_extent_m = 0.0;
};

// The flock's extent from the ADB's y positions (leader's view): the leader's rank r among the n
// agents sorted by y, at the formation's spacing: r * spacing below, (n - 1 - r) * spacing above.
// The rank, because a freshly launched flock is still spread out, capped by the measured span,
// because a formed flock settles a little under D_R1 apart (R1 only repels closer than D_R1; in
// the simulator 5 agents spanned ~28 m, not 30, and the outermost footprint missed the rectangle's
// edge by 0.3 m pass after pass).
FlockExtent flock_extent(double leader_y_m, const std::vector<double>& others_y_m,
                         double spacing_m);

struct PlannedPath {
  // the leader's control points, world ENU, in travel order; x strictly monotonic
  std::vector<Eigen::Vector2d> points_enu_m;
  double heading_rad = 0.0;  // 0 (+x) or pi (-x)
  bool low_side = true;      // planned on the low-y frontier
  // the frontier before translation (area frame: x = stripe centre, y = frontier), kept for tests
  std::vector<Eigen::Vector2d> frontier_m;
};

// One candidate: the frontier on one side, thresholded, smoothed and translated, in the direction
// that starts at the end nearer to leader_enu_m. Nothing when every stripe is covered.
std::optional<PlannedPath> plan_side(const CoverageConfig& config, const AreaParts& covered,
                                     const Eigen::Vector2d& leader_enu_m, const FlockExtent& extent,
                                     bool low_side);
// Both sides, the one whose start is nearer the leader kept.
std::optional<PlannedPath> plan_path(const CoverageConfig& config, const AreaParts& covered,
                                     const Eigen::Vector2d& leader_enu_m,
                                     const FlockExtent& extent);

// The path's y at x (linear between control points, constant beyond the ends).
double path_y_at(const PlannedPath& path, double x_enu_m);
// The way the path runs along x: +1 (towards +x) or -1.
double path_x_direction(const PlannedPath& path);

}  // namespace uavsim::missions::coverage
