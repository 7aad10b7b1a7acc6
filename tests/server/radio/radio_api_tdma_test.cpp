// The seed's TDMA through the API on both channel backends: the burst that saturates ns-3's CSMA-CA
// (RadioApi.OnNs3ASaturatedChannelShowsChannelAccessFailuresInTheStats) goes out whole, one frame
// per slot, when radio_config turns the slots on.
#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include "radio_server.hpp"
#include "uavsim/common/base64.hpp"

namespace uavsim::server::api {
namespace {

using testing::Json;
using testing::RadioServer;
using testing::TestClient;

class RadioApiTdma : public ::testing::TestWithParam<radio::Backend> {};

TEST_P(RadioApiTdma, ABurstGoesOutOneFramePerSlotWithoutChannelAccessFailures) {
  if (GetParam() == radio::Backend::kNs3 && !radio::find_ns3_helper()) {
    GTEST_SKIP() << "built without ns-3 (scripts/install_deps.sh)";
  }
  RadioServer server(GetParam());
  TestClient c(server.port());
  // mbzirc2020's two quads: 5 ms slots in a 100 ms period, 10 slots a period each
  const Json cfg =
      c.request({{"op", "radio_config"}, {"tdma", true}, {"slot_s", 0.005}, {"period_s", 0.1}});
  ASSERT_TRUE(cfg["ok"]) << cfg;
  EXPECT_EQ(cfg["result"]["tdma"], true);
  const std::string full = common::base64_encode(std::vector<uint8_t>(116, 7));
  for (int k = 0; k < 60; ++k) {
    for (int v = 0; v < 2; ++v) {
      const Json r = c.request(
          {{"op", "radio_send"}, {"vehicle", v}, {"to", "broadcast"}, {"data_b64", full}});
      ASSERT_TRUE(r["ok"]) << r;
    }
  }
  // 60 frames a vehicle: 6 periods of its slots, 0.6 s; step 0.3 s, then to 1 s
  ASSERT_TRUE(c.request({{"op", "step"}, {"duration_s", 0.3}})["ok"]);
  Json stats = c.request({{"op", "radio_stats"}});
  ASSERT_TRUE(stats["ok"]) << stats;
  for (const Json& v : stats["result"]["vehicles"]) {
    EXPECT_GT(v["queued"].get<int>(), 0) << stats;  // still waiting for their slots
  }
  ASSERT_TRUE(c.request({{"op", "step"}, {"duration_s", 0.7}})["ok"]);
  stats = c.request({{"op", "radio_stats"}});
  ASSERT_TRUE(stats["ok"]) << stats;
  for (const Json& v : stats["result"]["vehicles"]) {
    EXPECT_EQ(v["transmitted"], 60) << stats;
    EXPECT_EQ(v["channel_access_failures"], 0) << stats;
    EXPECT_EQ(v["queued"], 0) << stats;
    EXPECT_EQ(v["refused"], 0) << stats;
  }
}

INSTANTIATE_TEST_SUITE_P(Backends, RadioApiTdma,
                         ::testing::Values(radio::Backend::kSimple, radio::Backend::kNs3),
                         [](const auto& info) {
                           return info.param == radio::Backend::kNs3 ? "ns3" : "simple";
                         });

}  // namespace
}  // namespace uavsim::server::api
