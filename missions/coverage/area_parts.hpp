// Coverage bookkeeping (the thesis the project descends from, section 3.4): the rectangle is cut
// into stripes across the flight direction x, each a little shorter than the sensor footprint
// along x, so that one picture can cover a whole stripe. A picture is then a stripe index and the
// covered interval along y. Each agent keeps the pictures it took in an Area Parts Database (APD):
// one list of intervals per stripe, kept in normal form (sorted, disjoint, non-touching).
// Algorithm 4 normalises a stripe and unites two APDs. Pure: no clocks, no I/O.
#pragma once

#include <optional>
#include <vector>

#include "coverage_config.hpp"

namespace uavsim::missions::coverage {

// [start_m, end_m) along y, relative to the rectangle's origin.
struct Interval {
  double start_m = 0.0;
  double end_m = 0.0;
  bool operator==(const Interval&) const = default;
};

// Gaps narrower than this count as covered: the radio carries interval ends in 0.1 m steps, rounded
// inwards, so two abutting pictures may come back with a sliver between them.
inline constexpr double kCoverageSlack_m = 0.25;

// The length of a stripe's intervals inside [0, width_m].
double covered_length(const std::vector<Interval>& intervals, double width_m);

// Algorithm 4's NORMALIZE_STRIPE: the union of the patches as sorted, disjoint intervals (patches
// that overlap or touch become one). Empty or inverted patches are ignored.
std::vector<Interval> normalize_stripe(const std::vector<Interval>& patches);

class AreaParts {
 public:
  explicit AreaParts(int stripes = 0);

  int stripe_count() const { return static_cast<int>(stripes_.size()); }
  const std::vector<Interval>& stripe(int index) const { return stripes_.at(index); }

  // Adds one picture's interval to a stripe (kept in normal form); false if the index is out of
  // range (nothing changes).
  bool add(int stripe, Interval covered);
  // Algorithm 4's MERGE_APDS into this one; the stripe counts must match (false otherwise).
  // *changed, if given, says whether the union differs from what this held.
  bool merge(const AreaParts& other, bool* changed = nullptr);
  // Replaces a stripe's list (decoders); the list is normalised.
  bool set_stripe(int stripe, const std::vector<Interval>& intervals);
  bool set_stripe(int stripe, const Interval* intervals, size_t count);
  // Replaces the lists of stripes first .. first+stripes-1 with the same list, normalised (a
  // decoded run); false if any of them is out of range (nothing changes).
  bool set_stripes(int first, int stripes, const Interval* intervals, size_t count);
  // Empties every stripe; the stripe count stays, and so does the memory of the lists (a decoder
  // that fills the same AreaParts message after message allocates nothing once warm).
  void clear();

  // True when [start_m, end_m) of the stripe is covered (gaps under kCoverageSlack_m ignored).
  bool stripe_covers(int stripe, Interval span) const;
  // The lowest / highest y in [0, width_m] of the stripe not covered, if any.
  std::optional<double> lowest_uncovered(int stripe, double width_m) const;
  std::optional<double> highest_uncovered(int stripe, double width_m) const;
  // True when every stripe covers [0, width_m].
  bool covers_all(double width_m) const;
  // Covered fraction of the stripes' [0, width_m] (each stripe weighs the same).
  double covered_fraction(double width_m) const;

  bool operator==(const AreaParts&) const = default;

 private:
  std::vector<std::vector<Interval>> stripes_;
};

// What one picture covered.
struct Picture {
  int stripe = 0;
  Interval covered;
};

// The camera-trigger rule of section 3.6 for a downward sensor at the given pose (world ENU): the
// footprint (x_sensor x y_sensor about the agent) must intersect the rectangle, the sensor must be
// at the survey altitude and aligned with the x axis (heading +x or -x), the footprint must contain
// a whole stripe (it does not straddle a stripe boundary), and the interval must not be in `own`
// already. Returns the picture to store, or nothing.
std::optional<Picture> camera_trigger(const CoverageConfig& config, double x_enu_m, double y_enu_m,
                                      double altitude_m, double yaw_enu_rad, const AreaParts& own);

}  // namespace uavsim::missions::coverage
