#include "area_parts.hpp"

#include <algorithm>
#include <cmath>
#include <iterator>

namespace uavsim::missions::coverage {

namespace {

// Appends the union of intervals sorted by start to *out as sorted, disjoint, non-touching
// intervals: one that starts at or before the end of the one being built (overlapping or touching)
// extends it. Empty and inverted intervals (NaN ends too) are skipped.
template <typename It>
void sweep_sorted(It first, It last, std::vector<Interval>* out) {
  bool open = false;
  Interval cur;
  for (; first != last; ++first) {
    const Interval& p = *first;
    if (!(p.end_m > p.start_m)) continue;
    if (open && p.start_m <= cur.end_m) {
      cur.end_m = std::max(cur.end_m, p.end_m);
      continue;
    }
    if (open) out->push_back(cur);
    cur = p;
    open = true;
  }
  if (open) out->push_back(cur);
}

bool by_start(const Interval& a, const Interval& b) { return a.start_m < b.start_m; }

// True when the list is already in normal form (sorted, non-empty, disjoint, non-touching): what a
// decoder hands over from a well-formed message.
bool is_normal(const std::vector<Interval>& list) {
  for (size_t i = 0; i < list.size(); ++i) {
    if (!(list[i].end_m > list[i].start_m)) return false;
    if (i > 0 && !(list[i].start_m > list[i - 1].end_m)) return false;
  }
  return true;
}

// True when every interval of the normal list `part` lies inside one interval of the normal list
// `whole` (the union would be `whole` unchanged). Both sorted: one pass over each.
bool contains_all(const std::vector<Interval>& whole, const std::vector<Interval>& part) {
  size_t w = 0;
  for (const Interval& p : part) {
    while (w < whole.size() && whole[w].end_m < p.end_m) ++w;
    if (w == whole.size() || whole[w].start_m > p.start_m) return false;
  }
  return true;
}

}  // namespace

// Algorithm 4 builds a discontinuity map (+1 where a patch starts, -1 where one ends) and sweeps
// it; sorting the patches by start and extending while they overlap or touch gives the same union
// in the same normal form, without a tree node per end (this runs for every radio message an agent
// hears).
std::vector<Interval> normalize_stripe(const std::vector<Interval>& patches) {
  std::vector<Interval> sorted = patches;
  std::sort(sorted.begin(), sorted.end(), by_start);
  std::vector<Interval> result;
  sweep_sorted(sorted.begin(), sorted.end(), &result);
  return result;
}

double covered_length(const std::vector<Interval>& intervals, double width_m) {
  double sum = 0.0;
  for (const Interval& iv : intervals)
    sum += std::max(0.0, std::min(iv.end_m, width_m) - std::max(iv.start_m, 0.0));
  return sum;
}

AreaParts::AreaParts(int stripes) : stripes_(static_cast<size_t>(std::max(stripes, 0))) {}

bool AreaParts::add(int stripe, Interval covered) {
  if (stripe < 0 || stripe >= stripe_count()) return false;
  auto& list = stripes_[static_cast<size_t>(stripe)];
  list.push_back(covered);
  list = normalize_stripe(list);
  return true;
}

bool AreaParts::merge(const AreaParts& other, bool* changed) {
  if (changed) *changed = false;
  if (other.stripe_count() != stripe_count()) return false;
  std::vector<Interval> both;
  for (size_t i = 0; i < stripes_.size(); ++i) {
    std::vector<Interval>& mine = stripes_[i];
    const std::vector<Interval>& theirs = other.stripes_[i];
    // nothing new (the usual case once neighbours agree): the union is this stripe as it is
    if (contains_all(mine, theirs)) continue;
    // MERGE_APDS: the union of two normal lists; both are sorted, so a merge replaces the sort
    both.clear();
    std::merge(mine.begin(), mine.end(), theirs.begin(), theirs.end(), std::back_inserter(both),
               by_start);
    mine.clear();
    sweep_sorted(both.begin(), both.end(), &mine);
    if (changed) *changed = true;
  }
  return true;
}

bool AreaParts::set_stripe(int stripe, const std::vector<Interval>& intervals) {
  return set_stripe(stripe, intervals.data(), intervals.size());
}

bool AreaParts::set_stripe(int stripe, const Interval* intervals, size_t count) {
  return set_stripes(stripe, 1, intervals, count);
}

bool AreaParts::set_stripes(int first, int stripes, const Interval* intervals, size_t count) {
  if (first < 0 || stripes < 1 || stripes > stripe_count() - first) return false;
  const auto begin = stripes_.begin() + first, end = begin + stripes;
  // assign() into the lists' own memory: no allocation once a list has held as many intervals
  begin->assign(intervals, intervals + count);
  if (!is_normal(*begin)) *begin = normalize_stripe(*begin);
  for (auto it = begin + 1; it != end; ++it) *it = *begin;
  return true;
}

void AreaParts::clear() {
  for (auto& list : stripes_) list.clear();
}

bool AreaParts::stripe_covers(int stripe, Interval span) const {
  if (stripe < 0 || stripe >= stripe_count()) return false;
  double reached = span.start_m;  // everything below is covered
  for (const Interval& iv : stripes_[static_cast<size_t>(stripe)]) {
    if (iv.start_m > reached + kCoverageSlack_m) break;
    reached = std::max(reached, iv.end_m);
    if (reached >= span.end_m - kCoverageSlack_m) return true;
  }
  return reached >= span.end_m - kCoverageSlack_m;
}

std::optional<double> AreaParts::lowest_uncovered(int stripe, double width_m) const {
  if (stripe < 0 || stripe >= stripe_count()) return std::nullopt;
  double reached = 0.0;
  for (const Interval& iv : stripes_[static_cast<size_t>(stripe)]) {
    if (iv.start_m > reached + kCoverageSlack_m) break;
    reached = std::max(reached, iv.end_m);
  }
  if (reached >= width_m - kCoverageSlack_m) return std::nullopt;
  return reached;
}

std::optional<double> AreaParts::highest_uncovered(int stripe, double width_m) const {
  if (stripe < 0 || stripe >= stripe_count()) return std::nullopt;
  double reached = width_m;  // everything above is covered
  const auto& list = stripes_[static_cast<size_t>(stripe)];
  for (auto it = list.rbegin(); it != list.rend(); ++it) {
    if (it->end_m < reached - kCoverageSlack_m) break;
    reached = std::min(reached, it->start_m);
  }
  if (reached <= kCoverageSlack_m) return std::nullopt;
  return reached;
}

bool AreaParts::covers_all(double width_m) const {
  for (int i = 0; i < stripe_count(); ++i)
    if (!stripe_covers(i, {0.0, width_m})) return false;
  return true;
}

double AreaParts::covered_fraction(double width_m) const {
  if (stripes_.empty() || width_m <= 0.0) return 0.0;
  double sum = 0.0;
  for (const auto& list : stripes_) sum += covered_length(list, width_m);
  return sum / (width_m * static_cast<double>(stripes_.size()));
}

std::optional<Picture> camera_trigger(const CoverageConfig& config, double x_enu_m, double y_enu_m,
                                      double altitude_m, double yaw_enu_rad, const AreaParts& own) {
  // at the survey altitude, so that the footprint is x_sensor x y_sensor
  if (std::abs(altitude_m - config.altitude_m) > config.altitude_tolerance_m) return std::nullopt;
  // aligned with the x axis: |sin(yaw)| small means heading +x or -x (fig. 3.10b)
  if (std::abs(std::sin(yaw_enu_rad)) > std::sin(config.heading_tolerance_rad)) return std::nullopt;
  const double x = x_enu_m - config.origin_x_m;
  const double y = y_enu_m - config.origin_y_m;
  // the footprint must intersect the rectangle (fig. 3.10a)
  const double half_x = 0.5 * config.x_sensor_m, half_y = 0.5 * config.y_sensor_m;
  if (x + half_x <= 0.0 || x - half_x >= config.length_x_m) return std::nullopt;
  if (y + half_y <= 0.0 || y - half_y >= config.width_y_m) return std::nullopt;
  // the nearest stripe must lie whole inside the footprint (fig. 3.10c)
  const double h = config.stripe_height_m();
  const int n = config.stripe_count();
  const int stripe = std::clamp(static_cast<int>(std::floor(x / h)), 0, n - 1);
  const double s0 = stripe * h, s1 = s0 + h;
  if (x - half_x > s0 || x + half_x < s1) return std::nullopt;
  // clipped to the rectangle, and not acquired yet (fig. 3.10d)
  const Interval covered{std::max(0.0, y - half_y), std::min(config.width_y_m, y + half_y)};
  if (own.stripe_covers(stripe, covered)) return std::nullopt;
  return Picture{stripe, covered};
}

}  // namespace uavsim::missions::coverage
