// TDMA on the ns3 backend (radio/ns3_channel.hpp): the seed's slots (radio_model.hpp) with
// lr-wpan underneath. The server gives each frame the slot the simple model gives it and the helper
// puts it to the MAC at that slot's start, random backoff off: what contention lost under CSMA-CA
// goes through, each frame waits for its sender's slot only, and a seed gives the same deliveries.
// Needs the helper uavsim-ns3-radio (ctest label ns3).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <tuple>
#include <vector>

#include "ns3_test_support.hpp"
#include "radio/radio_model.hpp"

namespace uavsim::server::radio {
namespace {

// one clear-channel assessment (128 us) and the turnaround to transmit (192 us): how long after
// its slot's start a frame goes on air with macMinBE 0
constexpr double kAccess_s = 320e-6;
constexpr double kTol_s = 2e-6;
constexpr double kSlotIndexTol = 1e-3;
constexpr double kAirtimeTol_s = 1e-6;

RadioConfig tdma(double slot_s, double period_s) {
  RadioConfig c;
  c.tdma = true;
  c.slot_s = slot_s;
  c.period_s = period_s;
  return c;
}

TEST(Ns3Tdma, TenAudibleSendersInOneStepDeliverEverythingWithoutChannelAccessFailures) {
  // the burst that unslotted CSMA-CA delivers only in part (Ns3Radio.CsmaCaDeliversMostOf...):
  // with 5 ms slots in a 100 ms period each sender has one slot per round, so no two frames
  // overlap and none is given up
  const Burst csma = ten_senders_burst(Backend::kNs3, 1, {});
  const Burst slotted = ten_senders_burst(Backend::kNs3, 1, tdma(0.005, 0.1));
  std::printf("burst of 10: CSMA-CA %.3f delivered, %llu access failures; TDMA %.3f, %llu\n",
              csma.share, static_cast<unsigned long long>(csma.access_failures), slotted.share,
              static_cast<unsigned long long>(slotted.access_failures));
  EXPECT_LT(csma.share, 0.9);
  EXPECT_EQ(slotted.share, 1.0);
  EXPECT_EQ(slotted.access_failures, 0u);
  // the simple model's TDMA delivers the same frames (its collisions are on)
  const Burst simple = ten_senders_burst(Backend::kSimple, 1, tdma(0.005, 0.1));
  EXPECT_EQ(simple.share, 1.0);
}

TEST(Ns3Tdma, FramesGoOnAirInTheSlotsTheSimpleModelGivesThem) {
  // 4 vehicles, 10 ms slots in a 100 ms period: slot k (k * 10 ms into the period) is vehicle
  // k mod 4's, so vehicle 0 owns 0, 40 and 80 ms, vehicle 3 only 30 and 70 ms. Each sends a few
  // frames at odd times (vehicle 0 three at once: one per own slot), to a neighbour or to all
  const RadioConfig c = tdma(0.01, 0.1);
  const std::vector<Eigen::Vector3d> pos{{0, 0, 10}, {5, 0, 10}, {10, 0, 10}, {15, 0, 10}};
  auto deliveries = [&](Backend b) {
    auto ch = channel(b, pos.size(), c, 3);
    return std::pair{run(*ch, pos, 0.6,
                         [&](double t) {
                           const int64_t ms = std::llround(t / kStep_s);
                           if (ms == 31) ch->send(2, kBroadcast, frame(116), t);
                           if (ms == 47) {
                             for (int k = 0; k < 3; ++k) ch->send(0, 1, frame(20), t);
                           }
                           if (ms == 60) ch->send(1, kBroadcast, frame(1), t);  // at its slot
                           if (ms == 95) ch->send(3, 2, frame(60), t);          // next period
                         }),
                     ch->link(0, 1).no_ack};
  };
  // (sender, seq, receiver) order: ns-3 adds each receiver's propagation delay to its arrival
  auto by_frame = [](std::vector<Delivery> out) {
    std::sort(out.begin(), out.end(), [](const Delivery& a, const Delivery& b) {
      return std::tuple(a.from, a.seq, a.to) < std::tuple(b.from, b.seq, b.to);
    });
    return out;
  };
  const auto [simple_out, simple_no_ack] = deliveries(Backend::kSimple);
  const auto [ns3_out, ns3_no_ack] = deliveries(Backend::kNs3);
  const std::vector<Delivery> simple = by_frame(simple_out);
  const std::vector<Delivery> ns3 = by_frame(ns3_out);
  ASSERT_EQ(simple.size(), 3u + 3u + 3u + 1u);
  ASSERT_EQ(ns3.size(), simple.size());
  EXPECT_EQ(ns3_no_ack, 0u);  // the unicasts' ACKs come back within the slot
  for (size_t i = 0; i < ns3.size(); ++i) {
    const Delivery& s = simple[i];
    const Delivery& n = ns3[i];
    ASSERT_EQ(std::tuple(n.to, n.from, n.seq), std::tuple(s.to, s.from, s.seq)) << i;
    // the simple model starts it at its slot's start; ns-3 one assessment and turnaround later
    const double slot_s = tdma_slot_start_s(c, pos.size(), n.from, n.queued_s);
    EXPECT_GE(s.tx_start_s, slot_s - kTol_s);
    EXPECT_NEAR(n.tx_start_s, s.tx_start_s + kAccess_s, kTol_s) << i;
    // its sender's slot: a whole slot index k with k mod N = sender
    const double slot = std::fmod(s.tx_start_s + kTol_s, c.period_s) / c.slot_s;
    EXPECT_NEAR(slot, std::round(slot), kSlotIndexTol) << i;
    EXPECT_EQ(std::llround(std::floor(slot)) % 4, static_cast<int64_t>(n.from)) << i;
    // a frame sent to an empty queue waits less than 2 N D for a slot, then the access; the frame
    // arrives at the end of its airtime (no processing latency)
    if (n.seq == 0) EXPECT_LE(n.tx_start_s - n.queued_s, 2 * 4 * c.slot_s + kAccess_s) << i;
    EXPECT_NEAR(n.time_s, n.tx_start_s + airtime_s(n.data.size() + 11), kAirtimeTol_s) << i;
  }
  // vehicle 0's three unicasts at 47 ms: one per own slot, 80 ms, then 100 and 140 ms
  std::vector<double> starts;
  for (const Delivery& d : ns3) {
    if (d.from == 0) starts.push_back(d.tx_start_s);
  }
  ASSERT_EQ(starts.size(), 3u);
  EXPECT_NEAR(starts[0], 0.08 + kAccess_s, kTol_s);
  EXPECT_NEAR(starts[1], 0.10 + kAccess_s, kTol_s);
  EXPECT_NEAR(starts[2], 0.14 + kAccess_s, kTol_s);
}

TEST(Ns3Tdma, AFrameWaitsInTheServerUntilItsSlot) {
  // queued frames count against max_queue_frames while they wait, and go to the helper only at
  // the step before their slot: vehicle 1 of 2 owns 10-20 ms and 30-40 ms of a 40 ms period
  auto ch = channel(Backend::kNs3, 2, tdma(0.01, 0.04));
  const std::vector<Eigen::Vector3d> pos{{0, 0, 10}, {5, 0, 10}};
  std::vector<Delivery> out;
  ASSERT_TRUE(ch->send(1, 0, frame(10), 0.0).seq);
  for (int ms = 0; ms < 9; ++ms) ch->step(ms * kStep_s, pos, &out);
  EXPECT_EQ(ch->queued(1), 1u);
  EXPECT_EQ(ch->transmitted(1), 0u);
  for (int ms = 9; ms <= 20; ++ms) ch->step(ms * kStep_s, pos, &out);
  EXPECT_EQ(ch->transmitted(1), 1u);
  EXPECT_EQ(ch->queued(1), 0u);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_NEAR(out[0].tx_start_s, 0.01 + kAccess_s, kTol_s);
}

TEST(Ns3Tdma, TheSameSeedGivesIdenticalDeliveries) {
  // log-distance with shadowing: the draws are seeded, the slots fixed
  RadioConfig c = tdma(0.005, 0.1);
  c.propagation = Propagation::kLogDistance;
  const Burst a = ten_senders_burst(Backend::kNs3, 7, c);
  const Burst b = ten_senders_burst(Backend::kNs3, 7, c);
  ASSERT_FALSE(a.out.empty());
  ASSERT_EQ(a.out.size(), b.out.size());
  auto fields = [](const Delivery& d) {
    return std::tuple(d.to, d.from, d.seq, d.broadcast, d.queued_s, d.tx_start_s, d.time_s, d.data);
  };
  for (size_t i = 0; i < a.out.size(); ++i) EXPECT_EQ(fields(a.out[i]), fields(b.out[i])) << i;
}

TEST(Ns3Tdma, SlotSettingsAreRangeCheckedWithTheVehicleCount) {
  auto ch = channel(Backend::kNs3, 10, {});
  std::string why;
  // a period far beyond an hour: refused before any slot arithmetic
  EXPECT_FALSE(ch->set_config(config_for(Backend::kNs3, tdma(0.01, 1e12)), &why));
  EXPECT_NE(why.find("period_s"), std::string::npos) << why;
  EXPECT_FALSE(ch->set_config(config_for(Backend::kNs3, tdma(0.01, NAN)), &why));
  EXPECT_NE(why.find("period_s"), std::string::npos) << why;
  // 10 vehicles' slots of 10 ms do not fit in 50 ms
  EXPECT_FALSE(ch->set_config(config_for(Backend::kNs3, tdma(0.01, 0.05)), &why));
  EXPECT_NE(why.find("slot_s * vehicles"), std::string::npos) << why;
  EXPECT_FALSE(ch->set_config(config_for(Backend::kNs3, tdma(INFINITY, 1.0)), &why));
  EXPECT_NE(why.find("slot_s"), std::string::npos) << why;
  EXPECT_FALSE(ch->config().tdma);
  EXPECT_TRUE(
      ch->set_config(config_for(Backend::kNs3, tdma(Ns3Channel::min_tdma_slot_s(), 1.0)), &why))
      << why;
  EXPECT_TRUE(ch->config().tdma);
}

}  // namespace
}  // namespace uavsim::server::radio
