// The ns3 backend's second technology (technology "802.11": IEEE 802.11g ad hoc at a fixed
// 6 Mbit/s, ns-3's wifi module) against its 802.15.4: the same channel settings deliver to the same
// vehicles, far faster, with ACKs for unicast; the simple model refuses it; a seed gives the same
// deliveries. Needs the helper uavsim-ns3-radio (ctest label ns3).
#include <gtest/gtest.h>

#include <cstdio>
#include <tuple>
#include <vector>

#include "ns3_test_support.hpp"
#include "radio/radio_model.hpp"

namespace uavsim::server::radio {
namespace {

RadioConfig wifi(RadioConfig c = {}) {
  c.technology = Technology::k80211;
  return c;
}

TEST(Ns3Wifi, BroadcastReachesTheVehiclesInRangeWithinAMillisecond) {
  auto ch = channel(Backend::kNs3, 3, wifi());
  EXPECT_EQ(ch->max_payload_bytes(), 127u);  // the API's frame; 802.11 itself carries 2304
  const std::vector<Eigen::Vector3d> pos{{0, 0, 10}, {60, 0, 10}, {160, 0, 10}};
  bool sent = false;
  const auto out = run(*ch, pos, 0.05, [&](double t) {
    if (!sent) sent = ch->send(0, kBroadcast, frame(127), t).seq.has_value();
  });
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].to, 1u);
  EXPECT_EQ(out[0].data, frame(127));
  // DIFS, a backoff of at most 15 slots of 9 us and about 0.25 ms on air at 6 Mbit/s: the frame
  // arrives within the step after it was sent (802.15.4: 4.3 ms on air alone)
  EXPECT_LE(out[0].time_s - out[0].queued_s, kStep_s + 1e-9);
  EXPECT_GT(out[0].tx_start_s, out[0].queued_s);
  EXPECT_EQ(ch->link(0, 1).delivered, 1u);
  EXPECT_EQ(ch->link(0, 2).out_of_range, 1u);
  EXPECT_EQ(ch->transmitted(0), 1u);
  EXPECT_EQ(ch->queued(0), 0u);
}

TEST(Ns3Wifi, UnicastIsAckedInRangeAndGivenUpOutOfIt) {
  auto ch = channel(Backend::kNs3, 3, wifi());
  const std::vector<Eigen::Vector3d> pos{{0, 0, 10}, {60, 0, 10}, {160, 0, 10}};
  run(*ch, pos, 0.3, [&](double t) {
    if (every_ms(t, 10) && t < 0.2) ch->send(0, 1, frame(50), t);
    if (t == 0.0) ch->send(0, 2, frame(50), t);
  });
  EXPECT_EQ(ch->link(0, 1).delivered, 20u);
  EXPECT_EQ(ch->link(0, 1).no_ack, 0u);
  EXPECT_EQ(ch->link(0, 2).no_ack, 1u);  // out of range: no ACK after the retries
  EXPECT_EQ(ch->queued(0), 0u);
}

TEST(Ns3Wifi, ABurstInOneStepCollidesUnlessItsSendersSpreadIt) {
  // 802.11's DCF sends at once on a medium idle for DIFS, without 802.15.4's initial random
  // backoff: ten frames sent in the same step start together and collide. Sent 1 ms apart (each
  // 0.27 ms on air) they all go through
  const Burst lrwpan = ten_senders_burst(Backend::kNs3, 1, {});
  const Burst together = ten_senders_burst(Backend::kNs3, 1, wifi());
  constexpr size_t kN = 10;
  std::vector<Eigen::Vector3d> pos;
  for (size_t i = 0; i < kN; ++i) pos.emplace_back(5.0 * (i % 4), 5.0 * (i / 4), 10.0);
  auto ch = channel(Backend::kNs3, kN, wifi());
  const auto spread = run(*ch, pos, 2.1, [&](double t) {
    const int64_t ms = std::llround(t / kStep_s);
    if (ms < 2000 && ms % 100 < static_cast<int64_t>(kN)) {
      const auto i = static_cast<size_t>(ms % 100);
      ch->send(i, kBroadcast, frame(50, static_cast<uint8_t>(i)), t);
    }
  });
  const double spread_share = static_cast<double>(spread.size()) / (20.0 * kN * (kN - 1));
  std::printf("burst of 10: 802.15.4 %.3f delivered, 802.11 %.3f; 802.11 spread 1 ms: %.3f\n",
              lrwpan.share, together.share, spread_share);
  EXPECT_LT(together.share, 0.2);
  EXPECT_EQ(together.access_failures, 0u);
  EXPECT_EQ(spread_share, 1.0);
}

TEST(Ns3Wifi, TheSameSeedGivesTheSameDeliveries) {
  const Burst a = ten_senders_burst(Backend::kNs3, 11, wifi());
  const Burst b = ten_senders_burst(Backend::kNs3, 11, wifi());
  ASSERT_FALSE(a.out.empty());
  ASSERT_EQ(a.out.size(), b.out.size());
  auto fields = [](const Delivery& d) {
    return std::tuple(d.to, d.from, d.seq, d.queued_s, d.tx_start_s, d.time_s, d.data);
  };
  for (size_t i = 0; i < a.out.size(); ++i) EXPECT_EQ(fields(a.out[i]), fields(b.out[i])) << i;
}

TEST(Ns3Wifi, TheTechnologyChangesAtRunTimeAndOnlyOnNs3) {
  auto ch = channel(Backend::kNs3, 2, {});
  EXPECT_EQ(ch->max_payload_bytes(), 116u);
  std::string why;
  ASSERT_TRUE(ch->set_config(config_for(Backend::kNs3, wifi()), &why)) << why;
  EXPECT_EQ(ch->max_payload_bytes(), 127u);
  const std::vector<Eigen::Vector3d> pos{{0, 0, 10}, {5, 0, 10}};
  std::vector<Delivery> out;
  ASSERT_TRUE(ch->send(0, 1, frame(127), 1.0).seq);
  for (int k = 0; k <= 5; ++k) ch->step(1.0 + k * kStep_s, pos, &out);
  ASSERT_EQ(out.size(), 1u);
  // TDMA is 802.15.4's
  RadioConfig slotted = wifi();
  slotted.tdma = true;
  EXPECT_FALSE(ch->set_config(config_for(Backend::kNs3, slotted), &why));
  EXPECT_NE(why.find("tdma"), std::string::npos) << why;
  ASSERT_TRUE(ch->set_config(config_for(Backend::kNs3, {}), &why)) << why;
  EXPECT_EQ(ch->max_payload_bytes(), 116u);
  auto simple = channel(Backend::kSimple, 2, {});
  EXPECT_FALSE(simple->set_config(config_for(Backend::kSimple, wifi()), &why));
  EXPECT_NE(why.find("802.11"), std::string::npos) << why;
}

}  // namespace
}  // namespace uavsim::server::radio
