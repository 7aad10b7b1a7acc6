// The coverage run's score (run_score.hpp, the counts coverage-run prints and writes to its
// summary) against hand-computed runs: who survived and landed, the totals, the durations from the
// first take-off, when a run counts as a success, and the gaps listed in the held data.
#include "run_score.hpp"

#include <gtest/gtest.h>

#include <vector>

namespace uavsim::missions::coverage {
namespace {

constexpr double kExact = 1e-12;  // sums and differences of a few round numbers
constexpr bool kRunWentThrough = true;

// five quads that all landed, 100 to 500 mAh and 1000 to 5000 m
std::vector<VehicleOutcome> five_landed() {
  std::vector<VehicleOutcome> v;
  for (int i = 1; i <= 5; ++i) v.push_back({false, true, 100.0 * i, 1000.0 * i});
  return v;
}

// took off at 10 s, covered at 180 s, the last one down at 220 s
constexpr RunInstants kTimes{10.0, 220.0, 180.0};

TEST(RunScore, AFullRunOfLandedSurvivorsSucceeds) {
  const RunTally t = tally_run(five_landed(), kTimes, 1.0, kRunWentThrough);
  EXPECT_EQ(t.survivors, 5);
  EXPECT_EQ(t.landed, 5);
  EXPECT_EQ(t.failed, 0);
  // 100 + 200 + 300 + 400 + 500 = 1500 mAh, 15000 m
  EXPECT_NEAR(t.energy_total, 1500.0, kExact);
  EXPECT_NEAR(t.distance_total, 15000.0, kExact);
  // mission: 220 - 10 = 210 s; coverage: 180 - 10 = 170 s
  EXPECT_NEAR(t.mission_s, 210.0, kExact);
  EXPECT_NEAR(t.coverage_s, 170.0, kExact);
  EXPECT_DOUBLE_EQ(t.coverage, 1.0);
  EXPECT_TRUE(t.success);
}

TEST(RunScore, ADeadVehicleIsFailedNeverLandedYetItsFlightCounts) {
  std::vector<VehicleOutcome> v = five_landed();
  v[1].dead = true;  // 200 mAh, 2000 m; down (it fell), which a dead vehicle's landing never is
  const RunTally t = tally_run(v, kTimes, 1.0, kRunWentThrough);
  EXPECT_EQ(t.survivors, 4);
  EXPECT_EQ(t.landed, 4);
  EXPECT_EQ(t.failed, 1);
  EXPECT_NEAR(t.energy_total, 1500.0, kExact);
  EXPECT_NEAR(t.distance_total, 15000.0, kExact);
  EXPECT_TRUE(t.success);  // the four survivors landed with the area covered
}

TEST(RunScore, ASurvivorStillFlyingFailsTheRun) {
  std::vector<VehicleOutcome> v = five_landed();
  v[4].down = false;
  const RunTally t = tally_run(v, kTimes, 1.0, kRunWentThrough);
  EXPECT_EQ(t.survivors, 5);
  EXPECT_EQ(t.landed, 4);
  EXPECT_FALSE(t.success);
}

TEST(RunScore, SuccessNeedsFullCoverageASurvivorVehiclesAndARunThatWentThrough) {
  // 99.95 % is full (within the 1e-3 of rounding), 99.8 % is not
  EXPECT_TRUE(tally_run(five_landed(), kTimes, 0.9995, kRunWentThrough).success);
  EXPECT_FALSE(tally_run(five_landed(), kTimes, 0.998, kRunWentThrough).success);
  // every vehicle dead: no survivor, although "all survivors landed" holds for none
  std::vector<VehicleOutcome> dead = five_landed();
  for (VehicleOutcome& o : dead) o.dead = true;
  const RunTally t = tally_run(dead, kTimes, 1.0, kRunWentThrough);
  EXPECT_EQ(t.failed, 5);
  EXPECT_FALSE(t.success);
  // no vehicle reported, or the launcher failed or was interrupted
  EXPECT_FALSE(tally_run({}, kTimes, 1.0, kRunWentThrough).success);
  EXPECT_FALSE(tally_run(five_landed(), kTimes, 1.0, !kRunWentThrough).success);
}

TEST(RunScore, DurationsNeedATakeOffAndAnEndAfterIt) {
  const std::vector<VehicleOutcome> v = five_landed();
  // never took off: neither duration
  RunTally t = tally_run(v, {-1.0, 220.0, 180.0}, 1.0, kRunWentThrough);
  EXPECT_DOUBLE_EQ(t.mission_s, -1.0);
  EXPECT_DOUBLE_EQ(t.coverage_s, -1.0);
  // never landed, never completed: no end
  t = tally_run(v, {10.0, -1.0, -1.0}, 1.0, kRunWentThrough);
  EXPECT_DOUBLE_EQ(t.mission_s, -1.0);
  EXPECT_DOUBLE_EQ(t.coverage_s, -1.0);
  // a touchdown before the take-off (a vehicle landed at the start) is no mission time; the
  // completed query still counts: 50 - 10 = 40 s
  t = tally_run(v, {10.0, 5.0, 50.0}, 1.0, kRunWentThrough);
  EXPECT_DOUBLE_EQ(t.mission_s, -1.0);
  EXPECT_NEAR(t.coverage_s, 40.0, kExact);
  // take-off at t = 0 counts: 0 is an instant, not "never"
  t = tally_run(v, {0.0, 200.0, 150.0}, 1.0, kRunWentThrough);
  EXPECT_NEAR(t.mission_s, 200.0, kExact);
  EXPECT_NEAR(t.coverage_s, 150.0, kExact);
}

TEST(RunScoreGaps, ListsWhatTheHeldStripesMissBeyondTheSlack) {
  constexpr double kWidth_m = 100.0;
  AreaParts held(4);
  // stripe 0: a 0.1 m sliver at 40 m, under kCoverageSlack_m (0.25 m): no gap
  held.add(0, {0.0, 40.0});
  held.add(0, {40.1, 100.0});
  // stripe 1: missing 0-10 m and 50-60 m
  held.add(1, {10.0, 50.0});
  held.add(1, {60.0, 100.0});
  // stripe 2: nothing held; stripe 3: an interval past the far edge covers it all
  held.add(3, {0.0, 120.0});
  const std::vector<CoverageGap> gaps = coverage_gaps(held, kWidth_m, 20);
  ASSERT_EQ(gaps.size(), 3u);
  EXPECT_EQ(gaps[0].stripe, 1);
  EXPECT_DOUBLE_EQ(gaps[0].from_m, 0.0);
  EXPECT_DOUBLE_EQ(gaps[0].to_m, 10.0);
  EXPECT_EQ(gaps[1].stripe, 1);
  EXPECT_DOUBLE_EQ(gaps[1].from_m, 50.0);
  EXPECT_DOUBLE_EQ(gaps[1].to_m, 60.0);
  EXPECT_EQ(gaps[2].stripe, 2);
  EXPECT_DOUBLE_EQ(gaps[2].from_m, 0.0);
  EXPECT_DOUBLE_EQ(gaps[2].to_m, 100.0);
  // the list stops at max_gaps, in stripe order
  const std::vector<CoverageGap> first = coverage_gaps(held, kWidth_m, 2);
  ASSERT_EQ(first.size(), 2u);
  EXPECT_DOUBLE_EQ(first[1].from_m, 50.0);
  // the far edge is a gap too: a stripe held to 90 m misses 90-100 m
  AreaParts short_end(1);
  short_end.add(0, {0.0, 90.0});
  const std::vector<CoverageGap> end = coverage_gaps(short_end, kWidth_m, 20);
  ASSERT_EQ(end.size(), 1u);
  EXPECT_DOUBLE_EQ(end[0].from_m, 90.0);
  EXPECT_DOUBLE_EQ(end[0].to_m, 100.0);
}

}  // namespace
}  // namespace uavsim::missions::coverage
