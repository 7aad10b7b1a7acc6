// The launcher's measure of table 4.3's "distance flown to recover from failed agents": only the
// share of an agent's flight that photographs ground a failed agent alone held.
#include "recovery_meter.hpp"

#include <gtest/gtest.h>

#include <vector>

namespace uavsim::missions::coverage {
namespace {

constexpr int kStripes = 10;
constexpr double kWidth_m = 100.0;
constexpr double kLength_m = 150.0;  // stripes 15 m long along x
constexpr double kFractionTol = 1e-12;
constexpr double kDistanceTol_m = 1e-9;

// An APD with the same interval in stripes [first, last].
AreaParts band(int first, int last, double start_m, double end_m) {
  AreaParts apd(kStripes);
  for (int s = first; s <= last; ++s) apd.add(s, {start_m, end_m});
  return apd;
}

AreaParts unite(AreaParts a, const AreaParts& b) {
  a.merge(b);
  return a;
}

TEST(StripeSets, MinusAndIntersectionOfNormalFormLists) {
  const std::vector<Interval> a{{0, 10}, {20, 30}, {40, 50}};
  const std::vector<Interval> b{{5, 25}, {45, 60}};
  EXPECT_EQ(stripe_minus(a, b), (std::vector<Interval>{{0, 5}, {25, 30}, {40, 45}}));
  EXPECT_EQ(stripe_and(a, b), (std::vector<Interval>{{5, 10}, {20, 25}, {45, 50}}));
  EXPECT_EQ(stripe_minus(a, {}), a);
  EXPECT_TRUE(stripe_and(a, {}).empty());
  // an interval of b inside one of a splits it
  EXPECT_EQ(stripe_minus({{0, 10}}, {{2, 3}, {5, 6}}),
            (std::vector<Interval>{{0, 2}, {3, 5}, {6, 10}}));
}

TEST(RecoveryMeter, AgentPhotographingWhatAFailedAgentAloneHeldRecoversInProportion) {
  RecoveryMeter meter(kStripes, kWidth_m, kLength_m);
  // agent 1 alone holds y 10-20 over every stripe; agent 0 holds y 0-12 (2 m shared)
  meter.agent_report(0, band(0, 9, 0, 12));
  meter.agent_report(1, band(0, 9, 10, 20));
  // y 12-20: 8 m of 100 in every stripe
  EXPECT_NEAR(meter.agent_failed(1), 8.0 / 100.0, kFractionTol);
  EXPECT_NEAR(meter.lost_fraction(), 8.0 / 100.0, kFractionTol);
  // agent 0 photographs y 12-28 in every stripe: half of it (12-20) was lost, so half its flight
  // over the ten 15 m stripes
  meter.agent_report(0, band(0, 9, 0, 28));
  EXPECT_NEAR(meter.distance_m(), 75.0, kDistanceTol_m);
  EXPECT_NEAR(meter.recovered_fraction(), 0.08, kFractionTol);
  EXPECT_NEAR(meter.lost_fraction(), 0.0, kFractionTol);
  // ground recovered is no longer lost: flying over it again recovers nothing
  meter.agent_report(0, unite(band(0, 9, 0, 28), band(0, 4, 30, 40)));
  EXPECT_NEAR(meter.distance_m(), 75.0, kDistanceTol_m);
  // the failure's loss stays counted after its recovery; agent 0 now alone holds 0-28 and
  // 30-40 in half the stripes: lost with it, and lost a second time for y 12-20
  EXPECT_NEAR(meter.lost_at_failures_fraction(), 0.08, kFractionTol);
  EXPECT_NEAR(meter.agent_failed(0), 0.28 + 0.05, kFractionTol);
  EXPECT_NEAR(meter.lost_at_failures_fraction(), 0.08 + 0.33, kFractionTol);
}

TEST(RecoveryMeter, NothingIsLostWhileALiveAgentOrTheStationHoldsIt) {
  RecoveryMeter meter(kStripes, kWidth_m, kLength_m);
  meter.agent_report(0, band(0, 9, 0, 10));
  meter.agent_report(1, band(0, 9, 0, 10));  // the same ground as agent 0
  meter.agent_report(2, band(0, 9, 40, 50));
  meter.station_report(band(0, 9, 40, 50));  // agent 2's pictures were delivered
  EXPECT_EQ(meter.agent_failed(1), 0.0);
  EXPECT_EQ(meter.agent_failed(2), 0.0);
  EXPECT_EQ(meter.lost_fraction(), 0.0);
  EXPECT_EQ(meter.lost_at_failures_fraction(), 0.0);
  meter.agent_report(3, band(0, 9, 0, 60));
  EXPECT_EQ(meter.distance_m(), 0.0);
  EXPECT_EQ(meter.recovered_fraction(), 0.0);
}

TEST(RecoveryMeter, WithoutFailuresNothingIsRecoveredAndSliversAreNotLost) {
  RecoveryMeter meter(kStripes, kWidth_m, kLength_m);
  meter.agent_report(0, band(0, 9, 0, 10));
  meter.agent_report(1, band(0, 9, 10.1, 20));
  meter.agent_report(0, band(0, 9, 0, 30));
  EXPECT_EQ(meter.distance_m(), 0.0);
  // agent 1's 10.1-20 is under agent 0's 0-30 but for nothing; 30-... nothing else: no loss
  meter.agent_failed(1);
  EXPECT_EQ(meter.lost_fraction(), 0.0);
  // a 0.2 m sliver only the failed agent held is under the scoring's slack: not lost
  meter.agent_report(2, band(0, 9, 29.8, 40));
  meter.agent_report(3, band(0, 9, 30.2, 45));  // leaves 30.0-30.2 to agent 2 alone
  meter.agent_failed(2);
  EXPECT_EQ(meter.lost_fraction(), 0.0);
}

TEST(RecoveryMeter, AReportReadAfterTheFailureAddsToWhatIsLostAndTheFailedRecoverNothing) {
  RecoveryMeter meter(kStripes, kWidth_m, kLength_m);
  meter.agent_report(1, band(0, 9, 0, 10));
  EXPECT_NEAR(meter.agent_failed(1), 0.10, kFractionTol);
  EXPECT_EQ(meter.agent_failed(1), 0.0);  // the kill and its event both say so: counted once
  EXPECT_NEAR(meter.lost_fraction(), 0.10, kFractionTol);
  // its last pictures, printed before the kill and read after it
  meter.agent_report(1, band(0, 9, 0, 20));
  EXPECT_NEAR(meter.lost_fraction(), 0.20, kFractionTol);
  EXPECT_NEAR(meter.lost_at_failures_fraction(), 0.20, kFractionTol);
  EXPECT_EQ(meter.distance_m(), 0.0);
  // the station's later map (the recovering agent's pictures delivered before its own report)
  // does not hide the recovery
  meter.station_report(band(0, 9, 0, 20));
  meter.agent_report(0, band(0, 9, 0, 20));
  EXPECT_NEAR(meter.distance_m(), 150.0,
              kDistanceTol_m);  // all of its pictures, over ten 15 m stripes
  EXPECT_NEAR(meter.recovered_fraction(), 0.20, kFractionTol);
}

TEST(RecoveryMeter, ReportsOfAnotherStripeCountAreIgnored) {
  RecoveryMeter meter(kStripes, kWidth_m, kLength_m);
  meter.agent_report(0, AreaParts(kStripes + 1));
  meter.station_report(AreaParts(3));
  meter.agent_failed(0);
  EXPECT_EQ(meter.lost_fraction(), 0.0);
  EXPECT_EQ(meter.distance_m(), 0.0);
}

}  // namespace
}  // namespace uavsim::missions::coverage
