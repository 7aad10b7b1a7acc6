// The whole MBZIRC 2020 balloon mission (seed 7.2) with both UAVs' ground-station links over ns-3's
// 802.11 (mbzirc2020-run --gcs-link-backend ns3: every relayed datagram crosses the channel between
// the UAV and a ground node at the launch point, radio/gcs_radio_link.hpp). The mission does not
// use the A2A radio. Scored as mission_run_test.cpp scores the simple relay's run.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <string>

#include "../support/launcher_run.hpp"
#include "mission_expect.hpp"

namespace {

using Json = nlohmann::json;

constexpr double kBudget_s = 400.0;  // sim time, as mission_run_test.cpp

TEST(Mbzirc2020Ns3, TwoUavsPopAllFiveBalloonsOverAn80211GcsLink) {
  std::string out;
  const Json r =
      uavsim::tests::run_launcher(std::string(MBZIRC2020_RUN) + " --no-record --budget " +
                                      std::to_string(kBudget_s) + " --wall-limit 600",
                                  "--seed 1 --gcs-link-backend ns3", &out);
  ASSERT_TRUE(r.is_object()) << out;
  EXPECT_EQ(r["gcs_link_backend"], "ns3") << out;
  uavsim::tests::expect_all_five_popped(r, out, kBudget_s);
  // both links carried the mission's traffic over the radio, both ways
  ASSERT_EQ(r["gcs_links"].size(), 2u) << out;
  for (const Json& g : r["gcs_links"]) {
    EXPECT_EQ(g["backend"], "ns3") << g.dump();
    EXPECT_GT(g["to_gcs_forwarded"].get<int>(), 0) << g.dump();
    EXPECT_GT(g["to_uav_forwarded"].get<int>(), 0) << g.dump();
  }
}

}  // namespace
