// The GCS link over real UDP sockets on loopback, through the server's sim-time impairing relay
// (server/src/radio/gcs_relay.hpp): the same client code a UAV and a ground station run.
#include <gtest/gtest.h>

#include <chrono>
#include <set>

#include "radio/gcs_relay.hpp"
#include "uavsim/client/gcs_link.hpp"

namespace uavsim::client {
namespace {

constexpr int64_t kStep_us = 1000;
constexpr double kWallLimit_s = 30.0;  // a safety bound only; the run takes well under a second

TEST(GcsLinkRelay, EveryQueuedMessageCrossesALossyDelayedRelay) {
  std::string error;
  auto relay =
      server::radio::GcsRelay::open("127.0.0.1", 0, 0, std::nullopt, std::nullopt, 17, &error);
  ASSERT_TRUE(relay) << error;
  relay->impair(0.2, 0.05, 0.0, 0.0);  // 20% loss each way, 50 ms latency

  auto uav =
      GcsLink::open(GcsLinkConfig{2}, {"127.0.0.1", 0, "127.0.0.1", relay->uav_port()}, &error);
  ASSERT_TRUE(uav) << error;
  auto gcs = GcsLink::open(GcsLinkConfig{kGcsId}, {"127.0.0.1", 0, "127.0.0.1", relay->gcs_port()},
                           &error);
  ASSERT_TRUE(gcs) << error;

  // messages published over 4 s: one up every 20 ms, one down every 50 ms
  constexpr uint32_t kUp = 200, kDown = 80;
  uint32_t published_up = 0, published_down = 0;

  // one loop drives both ends and the relay on one clock (the sim's, for the relay)
  std::set<uint8_t> up, down;
  const auto wall_end =
      std::chrono::steady_clock::now() + std::chrono::duration<double>(kWallLimit_s);
  int64_t t_us = 0;
  bool outage_done = false;
  while ((up.size() < kUp || down.size() < kDown) && std::chrono::steady_clock::now() < wall_end) {
    t_us += kStep_us;
    if (published_up < kUp && t_us % 20000 == 0) {
      ASSERT_EQ(uav->publish(1, {uint8_t(published_up++)}), GcsLinkStatus::kOk);
    }
    if (published_down < kDown && t_us % 50000 == 0) {
      ASSERT_EQ(gcs->publish(2, {uint8_t(published_down++)}), GcsLinkStatus::kOk);
    }
    uav->service(t_us);
    gcs->service(t_us);
    relay->pump(static_cast<double>(t_us) * 1e-6);
    for (const GcsMessage& m : gcs->take_received()) up.insert(m.payload[0]);
    for (const GcsMessage& m : uav->take_received()) down.insert(m.payload[0]);
    // a 2 s outage once traffic flows: nothing queued is lost
    if (!outage_done && t_us == 1000000) {
      relay->impair(0.2, 0.05, 2.0, 1.0);
      outage_done = true;
    }
  }
  EXPECT_EQ(up.size(), kUp);
  EXPECT_EQ(down.size(), kDown);
  EXPECT_GE(t_us, 4000000);  // the last message was published at 4 s
  EXPECT_LT(t_us, 6000000);  // and arrived within a few periods
  EXPECT_GT(relay->stats().to_gcs_dropped, 0u);
  EXPECT_GT(relay->stats().to_uav_forwarded, 0u);
  // the UAV's clock estimate: both ends share one clock here, so the offset is the least delay (50
  // ms relay latency, read at 1 ms steps; slack for a datagram read a few steps late)
  ASSERT_TRUE(uav->core().clock_offset_us());
  EXPECT_GE(*uav->core().clock_offset_us(), 50000);
  EXPECT_LE(*uav->core().clock_offset_us(), 50000 + 10 * kStep_us);
}

TEST(GcsLinkRelay, BadAddressesAreReported) {
  std::string error;
  EXPECT_FALSE(GcsLink::open(GcsLinkConfig{1}, {"not-an-address", 0, "127.0.0.1", 1}, &error));
  EXPECT_NE(error.find("not-an-address"), std::string::npos);
  EXPECT_FALSE(
      server::radio::GcsRelay::open("300.0.0.1", 0, 0, std::nullopt, std::nullopt, 1, &error));
  EXPECT_NE(error.find("300.0.0.1"), std::string::npos);
}

}  // namespace
}  // namespace uavsim::client
