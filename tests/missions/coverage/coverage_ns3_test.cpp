// The coverage flock on the ns3 radio backend (ns-3's 802.15.4 in the uavsim-ns3-radio helper):
// the scenario of coverage_run_test (five quads over 150 x 100 m, seed 1) with CSMA-CA, SINR
// reception and frames of at most 116 bytes. The agents size their beacons (7 records, not 8) and
// aggregation fragments from the channel's frame size, so the radio refuses none of their frames;
// the mission completes, the same for a seed every time. 10-20 s of wall time a run.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <string>

#include "five_quads_run.hpp"

namespace {

using Json = nlohmann::json;

Json run_on_ns3(const std::string& extra, std::string* output) {
  return uavsim::tests::run_five_quads("--radio-backend ns3 " + extra, output);
}

TEST(CoverageNs3, FiveQuadsCoverTheRectangleAndLandOnNs3) {
  std::string out;
  const Json r = run_on_ns3("--seed 1", &out);
  ASSERT_TRUE(r.is_object()) << out;
  EXPECT_EQ(r["radio_backend"], "ns3") << out;
  // the channel was ns-3's with 116-byte frames, and it refused none of the agents' frames
  const Json& radio = r["radio"];
  EXPECT_EQ(radio["backend"], "ns3") << radio.dump();
  EXPECT_EQ(radio["max_frame_bytes"], 116) << radio.dump();
  EXPECT_EQ(radio["refused"], 0) << radio.dump();
  EXPECT_GT(radio["transmitted"].get<uint64_t>(), 1000u) << radio.dump();
  EXPECT_GT(radio["delivered"].get<uint64_t>(), 1000u) << radio.dump();
  // the mission: everything covered, everyone landed, nobody lost
  uavsim::tests::expect_complete_flock(r, 5, out);
}

// ns-3's backoffs and SINR draws come from the run's seed: the same seed gives the same mission,
// the whole summary to the byte (wall time and the run's paths aside), radio counters included.
TEST(CoverageNs3, SameSeedGivesTheSameWholeSummaryOnNs3) {
  std::string out[2];
  Json r[2];
  for (int k = 0; k < 2; ++k) {
    r[k] = run_on_ns3("--seed 2", &out[k]);
    ASSERT_TRUE(r[k].is_object()) << out[k];
    for (const char* field : {"wall_time_s", "run_dir", "video"}) r[k].erase(field);
  }
  EXPECT_GT(r[0]["radio"]["channel_access_failures"].get<uint64_t>(), 0u) << out[0];
  EXPECT_EQ(r[0].dump(2), r[1].dump(2)) << out[0] << out[1];
}

}  // namespace
