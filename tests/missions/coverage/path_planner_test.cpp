// Path planning of thesis 3.5: frontier, nearer side kept, threshold, smoothing, translation.
#include "path_planner.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "uavsim/common/angles.hpp"

namespace uavsim::missions::coverage {
namespace {

constexpr double kPosTol_m = 1e-9;
constexpr double kHeadingTol_rad = 1e-12;

// 10 stripes of 5.6 m over x in [0, 56), y in [0, 100)
CoverageConfig config() {
  CoverageConfig c;
  c.length_x_m = 56.0;
  c.width_y_m = 100.0;
  c.smoothing_half_window = 0;
  return c;
}

TEST(PathPlanner, FlockExtentFromTheLeadersRank) {
  // leader at y=10 with one agent below and three above, spacing 7.5
  const FlockExtent e = flock_extent(10.0, {2.0, 18.0, 25.0, 40.0}, 7.5);
  EXPECT_DOUBLE_EQ(e.low_extent_m, 7.5);
  EXPECT_DOUBLE_EQ(e.high_extent_m, 22.5);
}

TEST(PathPlanner, FlockExtentOfAFormedFlockIsItsMeasuredSpan) {
  // a formed flock settles a little under D_R1 apart (R1 only repels closer than that): four
  // agents 6.9 m apart above the leader span 27.6 m, not 4 * 7.5 = 30 m
  const FlockExtent e = flock_extent(10.0, {16.9, 23.8, 30.7, 37.6}, 7.5);
  EXPECT_DOUBLE_EQ(e.low_extent_m, 0.0);
  EXPECT_NEAR(e.high_extent_m, 27.6, kPosTol_m);
}

TEST(PathPlanner, EmptyMapLowSideTranslatesTheFlockEdgeOntoTheFrontierWithTheMargin) {
  const CoverageConfig c = config();
  const AreaParts empty(c.stripe_count());
  // leader at the low end of a 5-agent line (extent 0 below, 30 above), just before x = 0
  const auto p = plan_side(c, empty, {-10.0, 0.0}, {0.0, 30.0}, true);
  ASSERT_TRUE(p);
  // frontier y = 0 everywhere; leader y = 0 + 0 (extent) + 5 (half footprint) - 2 (20% of 10)
  for (const auto& q : p->points_enu_m) EXPECT_DOUBLE_EQ(q.y(), 3.0);
  // run-in: first stripe centre 2.8 - 2.8 - 7 = -7; run-out: 53.2 + 2.8 + 7 = 63; heading +x
  EXPECT_NEAR(p->points_enu_m.front().x(), -7.0, kPosTol_m);
  EXPECT_NEAR(p->points_enu_m.back().x(), 63.0, kPosTol_m);
  EXPECT_EQ(p->heading_rad, 0.0);
  EXPECT_EQ(p->points_enu_m.size(), 12u);  // 10 stripes + run-in + run-out
}

TEST(PathPlanner, HighSideAndDirectionFromTheNearerEnd) {
  const CoverageConfig c = config();
  AreaParts map(c.stripe_count());
  for (int i = 0; i < c.stripe_count(); ++i) map.add(i, {0.0, 40.0});
  // leader near the far end (x = 60) and high up: the high side starts nearer
  const FlockExtent e{30.0, 0.0};  // leader at the top of the line
  const auto p = plan_path(c, map, {60.0, 95.0}, e);
  ASSERT_TRUE(p);
  EXPECT_FALSE(p->low_side);
  // frontier 100; leader y = 100 - (0 + 5 - 2) = 97
  EXPECT_DOUBLE_EQ(p->points_enu_m.front().y(), 97.0);
  EXPECT_NEAR(p->heading_rad, common::kPi, kHeadingTol_rad);
  EXPECT_GT(p->points_enu_m.front().x(), p->points_enu_m.back().x());
  // low side from the same place would start at y = 40 + 30 + 3 = 73: farther than 97 from 95?
  // |73 - 95| = 22 > |97 - 95| = 2: the high side is the nearer one
  const auto low = plan_side(c, map, {60.0, 95.0}, e, true);
  ASSERT_TRUE(low);
  EXPECT_DOUBLE_EQ(low->points_enu_m.front().y(), 73.0);
}

TEST(PathPlanner, ThresholdDropsAnIsolatedHoleAndAKeptOneIsCoveredBySmoothing) {
  CoverageConfig c = config();
  AreaParts map(c.stripe_count());
  for (int i = 0; i < c.stripe_count(); ++i) map.add(i, {0.0, 40.0});
  map.set_stripe(4, {{0.0, 10.0}, {20.0, 40.0}});  // a hole at [10, 20) in stripe 4
  auto p = plan_side(c, map, {-10.0, 0.0}, {0.0, 0.0}, true);
  ASSERT_TRUE(p);
  // frontier 40 everywhere but 10 at stripe 4: 30 m from the median, not over the 30 m threshold
  EXPECT_DOUBLE_EQ(p->frontier_m[4].y(), 10.0);
  EXPECT_EQ(p->points_enu_m.size(), 12u);
  c.lateral_threshold_m = 20.0;
  p = plan_side(c, map, {-10.0, 0.0}, {0.0, 0.0}, true);
  ASSERT_TRUE(p);
  EXPECT_EQ(p->points_enu_m.size(), 11u);  // stripe 4 dropped
  for (const auto& q : p->points_enu_m) EXPECT_DOUBLE_EQ(q.y(), 43.0);
  // smoothing (+-1) with the hole kept: a plain average, (43 + 43 + 13) / 3 = 33 at the hole, would
  // leave its footprint's edge at 28, over the hole at 10. Within each window the points are first
  // pulled down to the hole's bound (13: the edge 2 m under it), so the hole's stripe stays at 13
  // and its neighbours average (43 + 13 + 13) / 3 = 23
  c.lateral_threshold_m = 100.0;
  c.smoothing_half_window = 1;
  p = plan_side(c, map, {-10.0, 0.0}, {0.0, 0.0}, true);
  ASSERT_TRUE(p);
  // points: run-in, stripes 0..9, run-out; stripe 3 is point 4
  EXPECT_DOUBLE_EQ(p->points_enu_m[4].y(), 23.0);
  EXPECT_DOUBLE_EQ(p->points_enu_m[5].y(), 13.0);
  EXPECT_DOUBLE_EQ(p->points_enu_m[6].y(), 23.0);
  EXPECT_DOUBLE_EQ(p->points_enu_m[2].y(), 43.0);  // stripe 1: its window holds no hole
  // the high side mirrors it: covered from 40 up, a hole at [10, 20) in stripe 4 is its highest
  // uncovered y only if nothing above is open; here the frontier is 100 everywhere (W), and the
  // whole band fits nowhere (the extent is zero), so nothing binds but the frontier
  p = plan_side(c, map, {-10.0, 0.0}, {0.0, 0.0}, false);
  ASSERT_TRUE(p);
  for (const auto& q : p->points_enu_m) EXPECT_DOUBLE_EQ(q.y(), c.width_y_m - 3.0);
}

TEST(PathPlanner, StripesAtTheEndsDroppedByTheThresholdAreStillFlownOver) {
  // the first two stripes covered up to 90 m (a flock still forming on its first pass spreads
  // wider), the rest up to 40 m: their frontier is 50 m off the median 40, over the 30 m threshold
  CoverageConfig c = config();
  AreaParts map(c.stripe_count());
  for (int i = 0; i < c.stripe_count(); ++i) map.add(i, {0.0, i < 2 ? 90.0 : 40.0});
  auto p = plan_side(c, map, {-10.0, 0.0}, {0.0, 30.0}, true);
  ASSERT_TRUE(p);
  EXPECT_EQ(p->points_enu_m.size(), 10u);  // stripes 2..9 + run-in + run-out
  // the run-in still starts a footprint before stripe 0 (centre 2.8 - 2.8 - 7 = -7), at the first
  // kept point's y (40 + 5 - 2): the flock passes over the dropped stripes without swinging
  EXPECT_NEAR(p->points_enu_m.front().x(), -7.0, kPosTol_m);
  EXPECT_DOUBLE_EQ(p->points_enu_m.front().y(), 43.0);
  EXPECT_NEAR(p->points_enu_m.back().x(), 63.0, kPosTol_m);
  EXPECT_DOUBLE_EQ(path_y_at(*p, 2.8), 43.0);
}

TEST(PathPlanner, ABandLeftThatFitsInsideTheSwathMovesItTowardsItsCentre) {
  // covered up to 80 m in every stripe: the band left is [80, 100], 20 m. A 5-agent line with the
  // leader at its bottom (extent 0 below, 30 above) sweeps 40 m: the band fits with 10 m to spare
  // on each side, so the swath [leader - 5, leader + 35] is centred on y = 90 (leader at 75), from
  // either side (8 m from the frontier rule's 83 and 67), instead of leaving 2 m of margin
  const CoverageConfig c = config();
  AreaParts map(c.stripe_count());
  for (int i = 0; i < c.stripe_count(); ++i) map.add(i, {0.0, 80.0});
  const FlockExtent e{0.0, 30.0};
  for (bool low : {true, false}) {
    const auto p = plan_side(c, map, {-10.0, 0.0}, e, low);
    ASSERT_TRUE(p);
    for (const auto& q : p->points_enu_m) EXPECT_DOUBLE_EQ(q.y(), 75.0) << "low side: " << low;
  }
  // the band [66, 100] with 2 m of margin on both sides fits the 40 m swath (34 + 4 <= 40): centred
  // on 83, leader at 68; [62, 100] does not (38 + 4 > 40): the frontier rule, 62 + 0 + 5 - 2 = 65
  for (int i = 0; i < c.stripe_count(); ++i) map.set_stripe(i, {{0.0, 66.0}});
  const auto p = plan_side(c, map, {-10.0, 0.0}, e, true);
  ASSERT_TRUE(p);
  EXPECT_DOUBLE_EQ(p->points_enu_m[1].y(), 68.0);
  for (int i = 0; i < c.stripe_count(); ++i) map.set_stripe(i, {{0.0, 62.0}});
  const auto q = plan_side(c, map, {-10.0, 0.0}, e, true);
  ASSERT_TRUE(q);
  EXPECT_DOUBLE_EQ(q->points_enu_m[1].y(), 65.0);
  // at most a footprint (10 m) from the frontier rule: band [90, 100], a 13-agent line (extent 0
  // below, 60 above): centred would be 65, the frontier rule says 93, the swath moves to 83
  for (int i = 0; i < c.stripe_count(); ++i) map.set_stripe(i, {{0.0, 90.0}});
  const auto r = plan_side(c, map, {-10.0, 0.0}, {0.0, 60.0}, true);
  ASSERT_TRUE(r);
  EXPECT_DOUBLE_EQ(r->points_enu_m[1].y(), 83.0);
}

TEST(PathPlanner, NothingToPlanWhenCovered) {
  const CoverageConfig c = config();
  AreaParts map(c.stripe_count());
  for (int i = 0; i < c.stripe_count(); ++i) map.add(i, {0.0, 100.0});
  EXPECT_FALSE(plan_path(c, map, {0.0, 0.0}, {}));
}

TEST(PathPlanner, PathYIsInterpolatedAlongX) {
  PlannedPath p;
  p.points_enu_m = {{0.0, 0.0}, {10.0, 10.0}, {20.0, 10.0}};
  EXPECT_DOUBLE_EQ(path_y_at(p, -5.0), 0.0);
  EXPECT_DOUBLE_EQ(path_y_at(p, 5.0), 5.0);
  EXPECT_DOUBLE_EQ(path_y_at(p, 25.0), 10.0);
  std::reverse(p.points_enu_m.begin(), p.points_enu_m.end());
  EXPECT_DOUBLE_EQ(path_y_at(p, 5.0), 5.0);
  EXPECT_DOUBLE_EQ(path_y_at(p, 25.0), 10.0);
}

}  // namespace
}  // namespace uavsim::missions::coverage
