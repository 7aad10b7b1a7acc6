// The coverage flock on the ns3 radio backend's 802.11 (802.11g ad hoc at 6 Mbit/s, DCF, in the
// uavsim-ns3-radio helper): ten quads over 300 x 300 m, the flock that stops at 92.9 % on ns3's
// 802.15.4 (docs/results/radio.md: its traffic does not fit 250 kbit/s). On 802.11 it covers the
// rectangle and lands, with the agents' frames entering the channel spread over the step (all of
// them are sent at the 20 Hz tick, where DCF would start them together). About a minute of wall
// time.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <string>

#include "five_quads_run.hpp"

namespace {

using Json = nlohmann::json;

constexpr double kBudget_s = 900.0;  // the mission takes about 450 s of sim time

TEST(CoverageWifi, TenQuadsCover300By300MetresAndLandOnNs3s80211) {
  std::string out;
  const Json r = uavsim::tests::run_launcher(
      std::string(COVERAGE_RUN) + " --agents 10 --area 300x300 --seed 1 --quiet --no-record " +
          "--radio-backend ns3 --radio-technology 802.11 --wall-limit 600 --budget " +
          std::to_string(kBudget_s),
      "", &out);
  ASSERT_TRUE(r.is_object()) << out;
  EXPECT_EQ(r["radio_technology"], "802.11") << out;
  const Json& radio = r["radio"];
  EXPECT_EQ(radio["backend"], "ns3") << radio.dump();
  EXPECT_EQ(radio["max_frame_bytes"], 1500) << radio.dump();
  EXPECT_EQ(radio["refused"], 0) << radio.dump();
  EXPECT_GT(radio["delivered"].get<uint64_t>(), 10000u) << radio.dump();
  uavsim::tests::expect_complete_flock(r, 10, out, kBudget_s);
}

}  // namespace
