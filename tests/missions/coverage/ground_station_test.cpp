// The optimised variant's ground station (thesis 3.6): it unites the agents' APDs and sends its
// map back at most once a period, only when it changed.
#include "ground_station.hpp"

#include <gtest/gtest.h>

#include "radio_messages.hpp"

namespace uavsim::missions::coverage {
namespace {

AreaParts one_interval(int stripes, int stripe, double a_m, double b_m) {
  AreaParts apd(stripes);
  apd.add(stripe, {a_m, b_m});
  return apd;
}

TEST(CoverageGroundStation, UnitesTheAgentsApdsIntoItsMap) {
  CoverageGroundStation gcs(10, 2.0);
  EXPECT_TRUE(gcs.on_agent_apd(encode_apd(one_interval(10, 2, 0.0, 10.0))));
  EXPECT_TRUE(gcs.on_agent_apd(encode_apd(one_interval(10, 2, 10.0, 20.0))));
  EXPECT_TRUE(gcs.on_agent_apd(encode_apd(one_interval(10, 7, 5.0, 6.0))));
  // stripe 2: [0, 10) and [10, 20) touch, so they are one interval (normal form)
  ASSERT_EQ(gcs.map().stripe(2).size(), 1u);
  EXPECT_EQ(gcs.map().stripe(2)[0], (Interval{0.0, 20.0}));
  EXPECT_EQ(gcs.map().stripe(7)[0], (Interval{5.0, 6.0}));
  EXPECT_EQ(gcs.apds_received(), 3);
  // an APD of another rectangle, or junk, changes nothing
  EXPECT_FALSE(gcs.on_agent_apd(encode_apd(one_interval(11, 2, 30.0, 40.0))));
  EXPECT_FALSE(gcs.on_agent_apd({1, 2, 3}));
  EXPECT_EQ(gcs.apds_received(), 3);
}

TEST(CoverageGroundStation, SendsItsMapAtMostOnceAPeriodAndOnlyWhenItChanged) {
  CoverageGroundStation gcs(10, 2.0);
  EXPECT_FALSE(gcs.poll_map(0.0));  // nothing received yet
  gcs.on_agent_apd(encode_apd(one_interval(10, 0, 0.0, 10.0)));
  const auto first = gcs.poll_map(0.5);
  ASSERT_TRUE(first);
  EXPECT_EQ(*decode_apd(*first, 10), gcs.map());
  gcs.on_agent_apd(encode_apd(one_interval(10, 1, 0.0, 10.0)));
  EXPECT_FALSE(gcs.poll_map(2.4));  // changed, but within the period of the last map (0.5 + 2)
  EXPECT_TRUE(gcs.poll_map(2.5));
  gcs.on_agent_apd(encode_apd(one_interval(10, 1, 0.0, 10.0)));  // nothing new
  EXPECT_FALSE(gcs.poll_map(10.0));
}

}  // namespace
}  // namespace uavsim::missions::coverage
