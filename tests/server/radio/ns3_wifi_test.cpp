// The ns3 backend's second technology (technology "802.11": IEEE 802.11g ad hoc at a fixed
// 6 Mbit/s, ns-3's wifi module) against its 802.15.4: the same channel settings deliver to the same
// vehicles, far faster, with ACKs for unicast; the simple model refuses it; a seed gives the same
// deliveries. Needs the helper uavsim-ns3-radio (ctest label ns3).
#include <gtest/gtest.h>

#include <cstdio>
#include <map>
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
  EXPECT_EQ(ch->max_payload_bytes(), 1500u);  // an Ethernet MTU (802.11's MSDU takes 2304)
  EXPECT_EQ(ch->send(0, kBroadcast, frame(1501), 0.0).error, Error::kFrameTooLarge);
  const std::vector<Eigen::Vector3d> pos{{0, 0, 10}, {60, 0, 10}, {160, 0, 10}};
  bool sent = false;
  const auto out = run(*ch, pos, 0.05, [&](double t) {
    if (!sent) sent = ch->send(0, kBroadcast, frame(127), t).seq.has_value();
  });
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].to, 1u);
  EXPECT_EQ(out[0].data, frame(127));
  // its entry within the step (the spread), DIFS, a backoff of at most 15 slots of 9 us and about
  // 0.25 ms on air at 6 Mbit/s: the frame arrives within two steps of being sent (802.15.4: 4.3 ms
  // on air alone)
  EXPECT_LE(out[0].time_s - out[0].queued_s, 2 * kStep_s + 1e-9);
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

TEST(Ns3Wifi, ABurstInOneStepIsSpreadOverTheStepAndMostOfItGetsThrough) {
  // 802.11's DCF sends at once on a medium idle for DIFS, without 802.15.4's initial random
  // backoff: ten frames entering the channel at the same instant would start together and
  // collide. They enter at seeded offsets within the step (send_spread_s, at least one step on
  // 802.11), as programs on clocks of their own would send them: a frame that finds the medium
  // busy defers and draws a backoff. Sent 1 ms apart (each 0.14 ms on air) they all go through;
  // spread over a 50 ms tick, nearly all
  const Burst lrwpan = ten_senders_burst(Backend::kNs3, 1, {});
  const Burst together = ten_senders_burst(Backend::kNs3, 1, wifi());
  RadioConfig tick = wifi();
  tick.send_spread_s = 0.05;
  const Burst over_a_tick = ten_senders_burst(Backend::kNs3, 1, tick);
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
  std::printf(
      "burst of 10: 802.15.4 %.3f delivered, 802.11 %.3f (over 50 ms: %.3f); 802.11 sent 1 ms "
      "apart: %.3f\n",
      lrwpan.share, together.share, over_a_tick.share, spread_share);
  EXPECT_GT(together.share, 0.6);
  EXPECT_GT(over_a_tick.share, 0.9);
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

TEST(Ns3Wifi, TheSpreadDependsOnTheSeedAndNotOnTheOrderOfTheSends) {
  // several senders' frames for the same tick, in any order, some before the gate's step
  // (starting_now false), two frames a sender (they keep their order); spread over 20 ms
  const std::vector<Eigen::Vector3d> pos{{0, 0, 10}, {5, 0, 10}, {10, 0, 10}, {15, 0, 10}};
  auto deliveries = [&](const std::vector<size_t>& order, bool gate_between, uint64_t seed) {
    RadioConfig c = wifi();
    c.send_spread_s = 0.02;
    auto ch = channel(Backend::kNs3, pos.size(), c, seed);
    std::vector<Delivery> out;
    for (int round = 0; round < 10; ++round) {
      const double t = round * 0.05;
      for (size_t k = 0; k < order.size(); ++k) {
        for (uint8_t n = 0; n < 2; ++n) {
          ch->send(order[k], kBroadcast, frame(40 + n, static_cast<uint8_t>(order[k])), t);
        }
        if (gate_between && k == 0) ch->step(t, pos, &out, false);
      }
      for (int s = 0; s < 50; ++s) ch->step(t + s * kStep_s, pos, &out);
    }
    return out;
  };
  auto fields = [](const Delivery& d) {
    return std::tuple(d.to, d.from, d.seq, d.tx_start_s, d.time_s, d.data);
  };
  const auto a = deliveries({0, 1, 2, 3}, false, 21);
  const auto b = deliveries({3, 1, 0, 2}, true, 21);
  const auto other = deliveries({0, 1, 2, 3}, false, 22);
  ASSERT_FALSE(a.empty());
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) EXPECT_EQ(fields(a[i]), fields(b[i])) << i;
  bool differs = a.size() != other.size();
  for (size_t i = 0; !differs && i < a.size(); ++i) differs = fields(a[i]) != fields(other[i]);
  EXPECT_TRUE(differs);
  // frames enter within the spread, a sender's in the order sent
  std::map<std::tuple<size_t, size_t>, std::pair<uint64_t, double>> last;  // (to, from) -> seq, t
  for (const Delivery& d : a) {
    EXPECT_GE(d.tx_start_s, d.queued_s);
    EXPECT_LT(d.tx_start_s, d.queued_s + 0.02 + 0.005);  // the spread, then DCF's deferrals
    const auto key = std::tuple(d.to, d.from);
    if (auto it = last.find(key); it != last.end()) {
      EXPECT_GT(d.seq, it->second.first);
      EXPECT_GE(d.tx_start_s, it->second.second);
    }
    last[key] = {d.seq, d.tx_start_s};
  }
}

TEST(Ns3Wifi, TheTechnologyChangesAtRunTimeAndOnlyOnNs3) {
  auto ch = channel(Backend::kNs3, 2, {});
  EXPECT_EQ(ch->max_payload_bytes(), 116u);
  std::string why;
  ASSERT_TRUE(ch->set_config(config_for(Backend::kNs3, wifi()), &why)) << why;
  EXPECT_EQ(ch->max_payload_bytes(), 1500u);
  const std::vector<Eigen::Vector3d> pos{{0, 0, 10}, {5, 0, 10}};
  std::vector<Delivery> out;
  ASSERT_TRUE(ch->send(0, 1, frame(1500), 1.0).seq);
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
  // the spread is the ns3 backend's, and not for TDMA's exact slots
  RadioConfig spread;
  spread.send_spread_s = 0.01;
  EXPECT_FALSE(simple->set_config(config_for(Backend::kSimple, spread), &why));
  EXPECT_NE(why.find("send_spread_s"), std::string::npos) << why;
  spread.tdma = true;
  EXPECT_FALSE(ch->set_config(config_for(Backend::kNs3, spread), &why));
  EXPECT_NE(why.find("send_spread_s"), std::string::npos) << why;
}

}  // namespace
}  // namespace uavsim::server::radio
