#include "path_planner.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace uavsim::missions::coverage {

namespace {

// The leader y whose swath covers a stripe's uncovered band with the margin: at most `hi` (the
// flock's low edge reaches the band's lowest y), at least `lo` (its high edge reaches the band's
// highest y). The frontier's side always binds; the far side only where the band fits inside the
// swath (elsewhere the next pass takes the rest).
struct SwathBounds {
  double lo = -std::numeric_limits<double>::infinity();
  double hi = std::numeric_limits<double>::infinity();
};

SwathBounds swath_bounds(const Eigen::Vector2d& band, const FlockExtent& extent, double y_sensor_m,
                         double margin_m, bool low_side, bool fits) {
  const double low_edge_max = band.x() + extent.low_extent_m + 0.5 * y_sensor_m - margin_m;
  const double high_edge_min = band.y() - extent.high_extent_m - 0.5 * y_sensor_m + margin_m;
  SwathBounds b;
  if (low_side || fits) b.hi = low_edge_max;
  if (!low_side || fits) b.lo = high_edge_min;
  return b;
}

// Moving average over +-k control points, the points first pulled inside bounds tightened to the
// whole window (the least upper and the greatest lower bound within +-k). Every average then keeps
// its own stripe's bounds: each of its 2k+1 terms lies within them, since each term's window holds
// this stripe. So the pass covers every frontier point it keeps (a plain average of a 23 m dip with
// its neighbours left 25 quads over 600 x 600 m, seed 3, a one-stripe hole under the next pass,
// closed only by a repair pass at the end: 30 s). Where the window's bounds cross (bands of
// different width side by side), the frontier's side wins.
void smooth_within_bounds(std::vector<Eigen::Vector2d>& points,
                          const std::vector<SwathBounds>& bounds, int k, bool low_side) {
  const int n = static_cast<int>(points.size());
  std::vector<double> pulled(static_cast<size_t>(n));
  for (int i = 0; i < n; ++i) {
    double lo = -std::numeric_limits<double>::infinity();
    double hi = std::numeric_limits<double>::infinity();
    for (int j = std::max(0, i - k); j <= std::min(n - 1, i + k); ++j) {
      lo = std::max(lo, bounds[static_cast<size_t>(j)].lo);
      hi = std::min(hi, bounds[static_cast<size_t>(j)].hi);
    }
    double y = points[static_cast<size_t>(i)].y();
    if (lo > hi) {
      y = low_side ? hi : lo;
    } else {
      y = std::clamp(y, lo, hi);
    }
    pulled[static_cast<size_t>(i)] = y;
  }
  for (int i = 0; i < n; ++i) {
    double sum = 0.0;
    int count = 0;
    for (int j = std::max(0, i - k); j <= std::min(n - 1, i + k); ++j) {
      sum += pulled[static_cast<size_t>(j)];
      ++count;
    }
    points[static_cast<size_t>(i)].y() = sum / count;
  }
}

}  // namespace

FlockExtent flock_extent(double leader_y_m, const std::vector<double>& others_y_m,
                         double spacing_m) {
  // the rank, capped by the measured span (a formed flock settles a little under D_R1 apart)
  int below = 0;
  double lowest = leader_y_m, highest = leader_y_m;
  for (double y : others_y_m) {
    if (y < leader_y_m) ++below;
    lowest = std::min(lowest, y);
    highest = std::max(highest, y);
  }
  const int above = static_cast<int>(others_y_m.size()) - below;
  return {std::min(below * spacing_m, leader_y_m - lowest),
          std::min(above * spacing_m, highest - leader_y_m)};
}

std::optional<PlannedPath> plan_side(const CoverageConfig& config, const AreaParts& covered,
                                     const Eigen::Vector2d& leader_enu_m, const FlockExtent& extent,
                                     bool low_side) {
  const double h = config.stripe_height_m();
  const double w = config.width_y_m;
  // the frontier: per stripe with something left, the lowest (highest) uncovered y; and the whole
  // band left in that stripe, from its lowest to its highest uncovered y
  std::vector<Eigen::Vector2d> frontier;
  std::vector<Eigen::Vector2d> band;  // (lowest, highest) uncovered y, one per frontier point
  for (int i = 0; i < covered.stripe_count(); ++i) {
    const auto lo = covered.lowest_uncovered(i, w);
    const auto hi = covered.highest_uncovered(i, w);
    if (!lo || !hi) continue;
    frontier.emplace_back((i + 0.5) * h, low_side ? *lo : *hi);
    band.emplace_back(*lo, *hi);
  }
  if (frontier.empty()) return std::nullopt;

  // threshold: drop control points more than lateral_threshold_m from the median frontier, which
  // would make the whole flock swing sideways for a few stripes (they stay uncovered and are
  // planned again after the next query, when they will be the median)
  std::vector<double> ys;
  for (const auto& p : frontier) ys.push_back(p.y());
  std::nth_element(ys.begin(), ys.begin() + ys.size() / 2, ys.end());
  const double median = ys[ys.size() / 2];
  // translation, per kept stripe: the leader's y that puts the flock's edge (its outermost agent's
  // footprint) over the frontier, overlapping it by the margin (extent + half a footprint - margin
  // inside it). Where the whole band left in the stripe fits inside the flock's swath with room to
  // spare, the swath moves towards the band's centre, by at most one footprint: a formation a few
  // metres narrower than the leader measured then still reaches the band's far side, the
  // rectangle's edge on the last pass (25 quads over 600 x 600 m, seed 3: with the 2 m margin alone
  // the last pass left 0.3-2.6 m along y = W over 25 stripes, two more passes, 153 s more). Not
  // centred outright: that lengthened the transit to the last pass and the flight home by 11 s.
  const double margin = config.edge_margin_fraction * config.y_sensor_m;
  const double offset = low_side ? extent.low_extent_m + 0.5 * config.y_sensor_m - margin
                                 : -(extent.high_extent_m + 0.5 * config.y_sensor_m - margin);
  const double swath = extent.low_extent_m + extent.high_extent_m + config.y_sensor_m;
  // per kept stripe: the leader's y, and the range of leader y whose swath reaches the frontier
  // (always) and the band's far side (where the band fits inside the swath)
  std::vector<Eigen::Vector2d> kept;  // (stripe centre x, the leader's y), area frame
  std::vector<SwathBounds> bounds;
  for (size_t i = 0; i < frontier.size(); ++i) {
    const Eigen::Vector2d& p = frontier[i];
    if (std::abs(p.y() - median) > config.lateral_threshold_m) continue;
    double y = p.y() + offset;
    const bool fits = band[i].y() - band[i].x() + 2.0 * margin <= swath;
    if (fits) {
      const double centred =
          0.5 * (band[i].x() + band[i].y()) - 0.5 * (extent.high_extent_m - extent.low_extent_m);
      y += std::clamp(centred - y, -config.y_sensor_m, config.y_sensor_m);
    }
    kept.emplace_back(p.x(), y);
    bounds.push_back(swath_bounds(band[i], extent, config.y_sensor_m, margin, low_side, fits));
  }
  smooth_within_bounds(kept, bounds, config.smoothing_half_window, low_side);

  PlannedPath path;
  path.low_side = low_side;
  path.frontier_m = frontier;
  for (const auto& p : kept)
    path.points_enu_m.emplace_back(config.origin_x_m + p.x(), config.origin_y_m + p.y());
  // run-in and run-out: start a footprint before the first frontier stripe's edge, end a footprint
  // past the last, so every agent's camera sweeps over both end stripes. The frontier's, not the
  // kept points': the threshold removes control points (the flock does not swing towards them), not
  // the stripes they stand for, and the thesis's flock runs "until the overall flock reaches the
  // other end" (3.5). Over the dropped end stripes the flock holds the end point's y; their
  // frontier, when it lies inside the swath, is covered on the way. (Ending at the last kept point
  // instead, 25 quads over 600 x 600 m left the first ~80 m of the second and third passes, whose
  // frontier lay over 30 m off the median, to three extra passes: 117 s of a 771 s mission.)
  const Eigen::Vector2d first = path.points_enu_m.front(), last = path.points_enu_m.back();
  const double x_first = config.origin_x_m + frontier.front().x();
  const double x_last = config.origin_x_m + frontier.back().x();
  path.points_enu_m.insert(path.points_enu_m.begin(),
                           {x_first - 0.5 * h - config.x_sensor_m, first.y()});
  path.points_enu_m.emplace_back(x_last + 0.5 * h + config.x_sensor_m, last.y());

  // direction: start at the end nearer to the leader
  if (std::abs(leader_enu_m.x() - path.points_enu_m.back().x()) <
      std::abs(leader_enu_m.x() - path.points_enu_m.front().x())) {
    std::reverse(path.points_enu_m.begin(), path.points_enu_m.end());
    path.heading_rad = kPi;
  }
  return path;
}

std::optional<PlannedPath> plan_path(const CoverageConfig& config, const AreaParts& covered,
                                     const Eigen::Vector2d& leader_enu_m,
                                     const FlockExtent& extent) {
  auto low = plan_side(config, covered, leader_enu_m, extent, true);
  auto high = plan_side(config, covered, leader_enu_m, extent, false);
  if (!low || !high) return low ? low : high;
  // keep the nearer start (ties: the low side)
  const double d_low = (low->points_enu_m.front() - leader_enu_m).norm();
  const double d_high = (high->points_enu_m.front() - leader_enu_m).norm();
  return d_high < d_low ? high : low;
}

double path_x_direction(const PlannedPath& path) {
  return std::cos(path.heading_rad) >= 0.0 ? 1.0 : -1.0;
}

double path_y_at(const PlannedPath& path, double x_enu_m) {
  const auto& p = path.points_enu_m;
  if (p.empty()) return 0.0;
  // points are monotonic in x, increasing or decreasing
  const bool increasing = p.back().x() >= p.front().x();
  auto before = [&](double a, double b) { return increasing ? a < b : a > b; };
  if (!before(p.front().x(), x_enu_m)) return p.front().y();
  for (size_t i = 1; i < p.size(); ++i) {
    if (!before(p[i].x(), x_enu_m)) {
      const double t = (x_enu_m - p[i - 1].x()) / (p[i].x() - p[i - 1].x());
      return p[i - 1].y() + t * (p[i].y() - p[i - 1].y());
    }
  }
  return p.back().y();
}

}  // namespace uavsim::missions::coverage
