// Coverage bookkeeping (thesis 3.4, Algorithm 4, fig. 3.7) and the camera-trigger rule (3.6).
#include "area_parts.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace uavsim::missions::coverage {
namespace {

TEST(NormalizeStripe, UnitesOverlappingAndTouchingPatchesLikeFig37) {
  // fig. 3.7's situation: patches in any order, some overlapping, some touching, one apart.
  // discontinuity map: 0:+1 5:+1 10:-1 15:-1 20:+1 30:-1+1=0 35:-1 40:+1 45:-1
  // running sum:       1    2    1     0     1     1        0     1     0
  // => intervals open at 0, 20, 40 and close at 15, 35, 45
  const std::vector<Interval> patches{{20, 30}, {0, 10}, {40, 45}, {5, 15}, {30, 35}};
  const std::vector<Interval> expected{{0, 15}, {20, 35}, {40, 45}};
  EXPECT_EQ(normalize_stripe(patches), expected);
}

TEST(NormalizeStripe, IgnoresEmptyAndInvertedPatches) {
  EXPECT_TRUE(normalize_stripe({{3, 3}, {5, 2}}).empty());
  EXPECT_EQ(normalize_stripe({{1, 4}, {2, 3}}), (std::vector<Interval>{{1, 4}}));
}

TEST(AreaParts, MergeIsTheUnionPerStripe) {
  AreaParts a(3), b(3);
  a.add(0, {0, 10});
  a.add(2, {50, 60});
  b.add(0, {8, 20});
  b.add(1, {30, 40});
  ASSERT_TRUE(a.merge(b));
  EXPECT_EQ(a.stripe(0), (std::vector<Interval>{{0, 20}}));
  EXPECT_EQ(a.stripe(1), (std::vector<Interval>{{30, 40}}));
  EXPECT_EQ(a.stripe(2), (std::vector<Interval>{{50, 60}}));
  EXPECT_FALSE(a.merge(AreaParts(4)));  // different stripe counts
}

TEST(AreaParts, FrontiersAreTheFirstUncoveredYFromEachSide) {
  AreaParts a(2);
  a.add(0, {0, 30});
  a.add(0, {60, 100});
  // stripe 0 covers [0,30) and [60,100): lowest uncovered 30, highest uncovered 60
  EXPECT_DOUBLE_EQ(*a.lowest_uncovered(0, 100), 30.0);
  EXPECT_DOUBLE_EQ(*a.highest_uncovered(0, 100), 60.0);
  // stripe 1 empty: 0 and 100
  EXPECT_DOUBLE_EQ(*a.lowest_uncovered(1, 100), 0.0);
  EXPECT_DOUBLE_EQ(*a.highest_uncovered(1, 100), 100.0);
  a.add(0, {29.9, 60.1});  // a slip of 0.1 m counts as covered (kCoverageSlack_m)
  a.add(1, {0, 49.9});
  a.add(1, {50.0, 100});
  EXPECT_FALSE(a.lowest_uncovered(0, 100));
  EXPECT_TRUE(a.covers_all(100));
  EXPECT_NEAR(a.covered_fraction(100), (100.0 + 99.9) / 200.0, 1e-9);
}

CoverageConfig small_area() {
  CoverageConfig c;
  c.length_x_m = 56.0;  // 56 / (0.8 * 7) = 10 stripes of 5.6 m
  c.width_y_m = 40.0;
  c.altitude_m = 20.0;
  return c;
}

TEST(CameraTrigger, StripesAreAFractionOfTheFootprint) {
  const CoverageConfig c = small_area();
  EXPECT_EQ(c.stripe_count(), 10);
  EXPECT_DOUBLE_EQ(c.stripe_height_m(), 5.6);
  EXPECT_EQ(c.validate(), "");
}

TEST(CameraTrigger, TakesAPictureOnlyWhenAllFourConditionsHold) {
  const CoverageConfig c = small_area();
  AreaParts own(c.stripe_count());
  // stripe 2 spans x in [11.2, 16.8), centre 14.0; the footprint [x-3.5, x+3.5] contains it for
  // x in [13.3, 14.7]
  auto p = camera_trigger(c, 14.0, 20.0, 20.0, 0.0, own);  // fig. 3.10d
  ASSERT_TRUE(p);
  EXPECT_EQ(p->stripe, 2);
  EXPECT_EQ(p->covered, (Interval{15.0, 25.0}));
  EXPECT_TRUE(camera_trigger(c, 14.6, 20.0, 20.0, 3.14159, own));  // heading -x is aligned too
  EXPECT_FALSE(camera_trigger(c, 14.0, 20.0, 20.0, 0.5, own));     // misaligned (3.10b)
  EXPECT_FALSE(camera_trigger(c, 16.8, 20.0, 20.0, 0.0, own));     // on a boundary (3.10c)
  EXPECT_FALSE(camera_trigger(c, 14.0, 60.0, 20.0, 0.0, own));     // outside (3.10a)
  EXPECT_FALSE(camera_trigger(c, 14.0, 20.0, 12.0, 0.0, own));     // not at Z_sensor
  // clipped at the rectangle's edge
  auto edge = camera_trigger(c, 14.0, 2.0, 20.0, 0.0, own);
  ASSERT_TRUE(edge);
  EXPECT_EQ(edge->covered, (Interval{0.0, 7.0}));
  // not acquired yet
  own.add(p->stripe, p->covered);
  EXPECT_FALSE(camera_trigger(c, 14.0, 20.0, 20.0, 0.0, own));
  EXPECT_TRUE(camera_trigger(c, 14.0, 24.0, 20.0, 0.0, own));  // [19, 29) is partly new
}

TEST(CoverageConfig, RejectsValuesOutOfRange) {
  CoverageConfig c;
  c.length_x_m = -5;
  EXPECT_NE(c.validate().find("length_x_m"), std::string::npos);
  c = CoverageConfig{};
  c.gains.kp_r3y = std::nan("");
  EXPECT_NE(c.validate().find("kp_r3y"), std::string::npos);
}

}  // namespace
}  // namespace uavsim::missions::coverage
