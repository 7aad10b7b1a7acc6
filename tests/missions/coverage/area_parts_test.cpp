// Coverage bookkeeping (thesis 3.4, Algorithm 4, fig. 3.7) and the camera-trigger rule (3.6).
#include "area_parts.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <random>

namespace uavsim::missions::coverage {
namespace {

constexpr double kFractionTol = 1e-9;

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
  EXPECT_NEAR(a.covered_fraction(100), (100.0 + 99.9) / 200.0, kFractionTol);
}

// Algorithm 4's NORMALIZE_STRIPE as the thesis writes it (a discontinuity map swept in increasing
// y): the oracle for the sort-and-sweep that the mission runs.
std::vector<Interval> algorithm4_normalize(const std::vector<Interval>& patches) {
  std::map<double, int> discont;
  for (const Interval& p : patches) {
    if (!(p.end_m > p.start_m)) continue;
    discont[p.start_m] += 1;
    discont[p.end_m] -= 1;
  }
  std::vector<Interval> result;
  int sum = 0;
  double start = 0.0;
  for (const auto& [y, delta] : discont) {
    const int prev = sum;
    sum += delta;
    if (prev == 0 && sum > 0) start = y;
    if (prev > 0 && sum == 0) result.push_back({start, y});
  }
  return result;
}

// Patches on a 0.5 m grid, so that ends often coincide (touching and shared ends are the cases
// that matter), some empty or inverted.
std::vector<Interval> random_patches(std::mt19937_64& rng, int count) {
  std::uniform_int_distribution<int> grid(0, 60), len(-2, 12);
  std::vector<Interval> out;
  for (int i = 0; i < count; ++i) {
    const double a = 0.5 * grid(rng);
    out.push_back({a, a + 0.5 * len(rng)});
  }
  return out;
}

TEST(NormalizeStripe, AgreesWithAlgorithm4OnRandomPatches) {
  std::mt19937_64 rng(7);
  for (int trial = 0; trial < 2000; ++trial) {
    const auto patches = random_patches(rng, 1 + trial % 12);
    ASSERT_EQ(normalize_stripe(patches), algorithm4_normalize(patches)) << "trial " << trial;
  }
}

TEST(AreaParts, MergeSaysWhetherTheUnionGrew) {
  std::mt19937_64 rng(11);
  for (int trial = 0; trial < 1000; ++trial) {
    AreaParts a(3), b(3);
    for (int s = 0; s < 3; ++s) {
      a.set_stripe(s, random_patches(rng, trial % 6));
      b.set_stripe(s, random_patches(rng, trial % 4));
    }
    AreaParts expected = a;
    for (int s = 0; s < 3; ++s) {
      std::vector<Interval> both = a.stripe(s);
      both.insert(both.end(), b.stripe(s).begin(), b.stripe(s).end());
      expected.set_stripe(s, algorithm4_normalize(both));
    }
    const AreaParts before = a;
    bool changed = true;
    ASSERT_TRUE(a.merge(b, &changed));
    ASSERT_EQ(a, expected) << "trial " << trial;
    ASSERT_EQ(changed, !(a == before)) << "trial " << trial;
  }
  // a part already held changes nothing
  AreaParts whole(1), part(1);
  whole.add(0, {0, 10});
  part.add(0, {2, 10});
  bool changed = true;
  ASSERT_TRUE(whole.merge(part, &changed));
  EXPECT_FALSE(changed);
  part.add(0, {10, 11});  // touching: one interval [2, 11) that reaches past
  ASSERT_TRUE(whole.merge(part, &changed));
  EXPECT_TRUE(changed);
  EXPECT_EQ(whole.stripe(0), (std::vector<Interval>{{0, 11}}));
}

TEST(AreaParts, SetStripeNormalisesAListThatIsNotInNormalForm) {
  AreaParts a(1);
  a.set_stripe(0, {{5, 8}, {0, 5}, {7, 9}, {20, 10}});  // unsorted, touching, inverted
  EXPECT_EQ(a.stripe(0), (std::vector<Interval>{{0, 9}}));
  a.set_stripe(0, {{0, 1}, {2, 3}});  // already normal: kept as it is
  EXPECT_EQ(a.stripe(0), (std::vector<Interval>{{0, 1}, {2, 3}}));
}

TEST(AreaParts, SetStripesSetsARunOfStripesOrNothing) {
  AreaParts a(5);
  a.add(0, {1, 2});
  const std::vector<Interval> run{{5, 8}, {0, 5}, {30, 40}};  // not normal: normalised once
  ASSERT_TRUE(a.set_stripes(1, 3, run.data(), run.size()));
  EXPECT_EQ(a.stripe(0), (std::vector<Interval>{{1, 2}}));
  for (int s = 1; s < 4; ++s) EXPECT_EQ(a.stripe(s), (std::vector<Interval>{{0, 8}, {30, 40}}));
  EXPECT_TRUE(a.stripe(4).empty());
  const AreaParts before = a;
  EXPECT_FALSE(a.set_stripes(3, 3, run.data(), run.size()));  // past the last stripe
  EXPECT_FALSE(a.set_stripes(-1, 2, run.data(), run.size()));
  EXPECT_FALSE(a.set_stripes(0, 0, run.data(), run.size()));
  EXPECT_EQ(a, before);
  ASSERT_TRUE(a.set_stripes(2, 1, nullptr, 0));  // an empty list empties the stripe
  EXPECT_TRUE(a.stripe(2).empty());
}

TEST(AreaParts, ClearEmptiesEveryStripeAndKeepsTheCount) {
  AreaParts a(3);
  a.add(0, {0, 10});
  a.add(2, {4, 5});
  a.clear();
  EXPECT_EQ(a, AreaParts(3));
  EXPECT_EQ(a.stripe_count(), 3);
  a.add(1, {2, 3});  // usable as before
  EXPECT_EQ(a.stripe(1), (std::vector<Interval>{{2, 3}}));
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
