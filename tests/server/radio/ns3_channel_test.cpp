// The ns3 radio backend (radio/ns3_channel.hpp) against the simple one: the same scenarios on both
// channels, stepped at 1 kHz with fixed positions. Parity where the two should agree (one sender's
// delivery against distance, latency within the CSMA-CA bound), and what only ns-3 models:
// contention under CSMA-CA, hidden terminals, capture, saturation; determinism; a helper that dies
// or hangs. Needs the helper uavsim-ns3-radio (built when ns-3 is installed; ctest label ns3).
#include "radio/ns3_channel.hpp"

#include <gtest/gtest.h>
#include <signal.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <memory>
#include <tuple>
#include <vector>

#include "ns3_test_support.hpp"
#include "radio/radio_model.hpp"
#include "radio/sim_radio.hpp"

namespace uavsim::server::radio {
namespace {

constexpr double kRangeRelTol = 0.1;

TEST(Ns3Radio, FramesCarry116BytesWithShortAddresses) {
  // 127-byte PSDU - 11 bytes of header and FCS = 116 (lr-wpan refuses 117 and 118 with short
  // addresses: its own 118 limit assumes a header without addresses)
  auto ch = channel(Backend::kNs3, 2, {});
  EXPECT_STREQ(ch->backend_name(), "ns3");
  EXPECT_EQ(ch->max_payload_bytes(), 116u);
  EXPECT_TRUE(ch->send(0, 1, frame(116), 0.0).seq);
  EXPECT_EQ(ch->send(0, 1, frame(117), 0.0).error, Error::kFrameTooLarge);
  // the simple model accounts for the same header when told to
  auto simple = channel(Backend::kSimple, 2, {});
  EXPECT_EQ(simple->max_payload_bytes(), 116u);
  EXPECT_EQ(RadioModel(2, RadioConfig{}, 1, kStep_s).max_payload_bytes(), 127u);  // the default
}

TEST(Ns3Radio, BroadcastReachesTheVehiclesInRangeWithinTheCsmaBound) {
  RadioConfig c;
  c.range_m = 100.0;
  auto ch = channel(Backend::kNs3, 3, c);
  const std::vector<Eigen::Vector3d> pos{{0, 0, 10}, {60, 0, 10}, {160, 0, 10}};
  bool sent = false;
  const auto out = run(*ch, pos, 0.05, [&](double t) {
    if (!sent) sent = ch->send(0, kBroadcast, frame(116), t).seq.has_value();
  });
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].to, 1u);
  EXPECT_EQ(out[0].from, 0u);
  EXPECT_EQ(out[0].data, frame(116));
  // unslotted CSMA-CA, macMinBE 3: at most 7 backoff periods of 320 us, CCA 128 us, turnaround
  // 192 us before the frame; (116 + 11 + 6) * 8 / 250 kbit/s = 4.256 ms on air; one step of
  // stepping on top
  const double airtime = airtime_s(116 + 11);
  EXPECT_GE(out[0].time_s - out[0].queued_s, airtime);
  EXPECT_LE(out[0].time_s - out[0].queued_s, airtime + 7 * 320e-6 + 128e-6 + 192e-6 + kStep_s);
  EXPECT_EQ(ch->link(0, 1).delivered, 1u);
  EXPECT_EQ(ch->link(0, 2).out_of_range, 1u);
  EXPECT_EQ(ch->transmitted(0), 1u);
}

// the distance where delivery falls through 50 % (linear between the sweep's points)
double half_delivery_distance(Backend b) {
  RadioConfig c;
  c.propagation = Propagation::kLogDistance;
  c.shadowing_sigma_db = 4.0;
  // one sender, receivers at 30, 35, ..., 100 m (spread round it: none near another's path)
  std::vector<Eigen::Vector3d> pos{{0, 0, 10}};
  std::vector<double> dist;
  for (double d = 30.0; d <= 100.0; d += 5.0) {
    const double a = 0.4 * static_cast<double>(dist.size());
    pos.emplace_back(d * std::cos(a), d * std::sin(a), 10.0);
    dist.push_back(d);
  }
  auto ch = channel(b, pos.size(), c, 3);
  constexpr int kFrames = 300;
  int sent = 0;
  run(*ch, pos, kFrames * 0.02 + 0.05, [&](double t) {
    if (sent < kFrames && every_ms(t, 20))
      sent += ch->send(0, kBroadcast, frame(50), t).seq ? 1 : 0;
  });
  std::vector<double> rate;
  for (size_t r = 1; r < pos.size(); ++r) {
    rate.push_back(static_cast<double>(ch->link(0, r).delivered) / kFrames);
  }
  for (size_t i = 1; i < rate.size(); ++i) {
    if (rate[i - 1] >= 0.5 && rate[i] < 0.5) {
      return dist[i - 1] + (dist[i] - dist[i - 1]) * (rate[i - 1] - 0.5) / (rate[i - 1] - rate[i]);
    }
  }
  return -1.0;
}

TEST(Ns3Radio, HalfDeliveryDistanceMatchesTheSimpleModel) {
  // log-distance, 0 dBm, -85 dBm, 40.05 dB at 1 m, n = 2.5, sigma 4 dB: the mean path loss meets
  // the budget at 10^((85 - 40.05) / 25) = 62.9 m, where half the frames get through
  const double simple_m = half_delivery_distance(Backend::kSimple);
  const double ns3_m = half_delivery_distance(Backend::kNs3);
  std::printf("half-delivery distance: simple %.1f m, ns3 %.1f m\n", simple_m, ns3_m);
  EXPECT_NEAR(simple_m, 62.9, 62.9 * kRangeRelTol);
  EXPECT_NEAR(ns3_m, simple_m, simple_m * kRangeRelTol)
      << "simple " << simple_m << " m, ns3 " << ns3_m << " m";
}

// the share of (frame, receiver) pairs of ten_senders_burst delivered
double contention_share(Backend b, uint64_t seed, std::vector<Delivery>* out_all = nullptr) {
  const Burst burst = ten_senders_burst(b, seed, {});
  if (out_all != nullptr) *out_all = burst.out;
  return burst.share;
}

TEST(Ns3Radio, CsmaCaDeliversMostOfABurstTheSimpleModelLosesToCollisions) {
  // simple: all ten start together and overlap everywhere; ns-3: random backoff spreads them
  const double simple = contention_share(Backend::kSimple, 1);
  const double ns3 = contention_share(Backend::kNs3, 1);
  std::printf("contention, share delivered: simple %.3f, ns3 %.3f\n", simple, ns3);
  EXPECT_LT(simple, 0.05);
  EXPECT_GT(ns3, simple + 0.4) << "simple " << simple << ", ns3 " << ns3;
}

// A and C both broadcast to B in the same step, every 50 ms; A-C apart by c_x_m; the share of their
// frames B loses
double loss_at_b(double c_x_m) {
  RadioConfig c;
  c.range_m = 100.0;
  const std::vector<Eigen::Vector3d> pos{{0, 0, 10}, {c_x_m / 2, 0, 10}, {c_x_m, 0, 10}};
  auto ch = channel(Backend::kNs3, 3, c, 5);
  constexpr int kRounds = 60;
  int rounds = 0;
  run(*ch, pos, kRounds * 0.05 + 0.05, [&](double t) {
    if (rounds >= kRounds || !every_ms(t, 50)) return;
    ++rounds;
    ch->send(0, kBroadcast, frame(100), t);
    ch->send(2, kBroadcast, frame(100), t);
  });
  const double delivered = static_cast<double>(ch->link(0, 1).delivered + ch->link(2, 1).delivered);
  return 1.0 - delivered / (2.0 * kRounds);
}

TEST(Ns3Radio, HiddenTerminalsLoseFarMoreThanSendersThatHearEachOther) {
  // 60 m apart A and C hear each other and defer (CSMA-CA); 160 m apart (range 100 m) they cannot,
  // and their frames overlap at B in the middle
  const double audible = loss_at_b(60.0);
  const double hidden = loss_at_b(160.0);
  std::printf("loss at B: audible %.3f, hidden %.3f\n", audible, hidden);
  EXPECT_LT(audible, 0.3);
  EXPECT_GT(hidden, audible + 0.3) << "audible " << audible << ", hidden " << hidden;
}

TEST(Ns3Radio, TheNearFrameSurvivesAFarOverlap) {
  // R at the origin, N 5 m away, F 60 m away on the other side (N and F cannot hear each other:
  // 65 m, past the 62.9 m budget): both send in the same step. At R, N is 27 dB stronger
  // (25 log10(60 / 5)), so whenever R locks onto N first, N's frame decodes through F's. The simple
  // model loses both to the overlap.
  RadioConfig c;
  c.propagation = Propagation::kLogDistance;
  c.shadowing_sigma_db = 0.0;
  const std::vector<Eigen::Vector3d> pos{{0, 0, 10}, {-5, 0, 10}, {60, 0, 10}};
  auto count_near = [&](Backend b) {
    auto ch = channel(b, 3, c, 9);
    constexpr int kRounds = 60;
    int rounds = 0;
    run(*ch, pos, kRounds * 0.05 + 0.05, [&](double t) {
      if (rounds >= kRounds || !every_ms(t, 50)) return;
      ++rounds;
      ch->send(1, kBroadcast, frame(100), t);
      ch->send(2, kBroadcast, frame(100), t);
    });
    return std::pair{static_cast<double>(ch->link(1, 0).delivered) / kRounds,
                     static_cast<double>(ch->link(2, 0).delivered) / kRounds};
  };
  const auto [simple_near, simple_far] = count_near(Backend::kSimple);
  const auto [ns3_near, ns3_far] = count_near(Backend::kNs3);
  std::printf("capture, share delivered at R: simple near %.3f far %.3f, ns3 near %.3f far %.3f\n",
              simple_near, simple_far, ns3_near, ns3_far);
  EXPECT_EQ(simple_near, 0.0);
  EXPECT_GT(ns3_near, 0.3) << "far " << ns3_far;
}

TEST(Ns3Radio, OfferedLoadBeyondTheChannelGivesChannelAccessFailures) {
  // 10 senders queue 20 full frames each at once: 200 * 4.256 ms = 0.85 s of airtime offered in
  // one step; CCA keeps finding the channel busy, and after macMaxCSMABackoffs (4) retries a frame
  // is given up
  constexpr size_t kN = 10;
  std::vector<Eigen::Vector3d> pos;
  for (size_t i = 0; i < kN; ++i) pos.emplace_back(3.0 * i, 0.0, 10.0);
  auto ch = channel(Backend::kNs3, kN, {});
  run(*ch, pos, 1.5, [&](double t) {
    if (t != 0.0) return;
    for (int k = 0; k < 20; ++k) {
      for (size_t i = 0; i < kN; ++i) ch->send(i, kBroadcast, frame(116), t);
    }
  });
  uint64_t failures = 0, transmitted = 0;
  for (size_t i = 0; i < kN; ++i) {
    failures += ch->channel_access_failures(i);
    transmitted += ch->transmitted(i);
    EXPECT_EQ(ch->queued(i), 0u);  // every frame confirmed, sent or given up
  }
  std::printf("saturation: %llu channel-access failures, %llu transmitted of %zu\n",
              static_cast<unsigned long long>(failures),
              static_cast<unsigned long long>(transmitted), kN * 20);
  EXPECT_GT(failures, 20u);
  EXPECT_EQ(failures + transmitted, kN * 20);
}

TEST(Ns3Radio, TheSameSeedGivesTheSameDeliveriesFieldByField) {
  std::vector<Delivery> a, b, other;
  contention_share(Backend::kNs3, 11, &a);
  contention_share(Backend::kNs3, 11, &b);
  contention_share(Backend::kNs3, 12, &other);
  ASSERT_EQ(a.size(), b.size());
  ASSERT_FALSE(a.empty());
  auto fields = [](const Delivery& d) {
    return std::tuple(d.to, d.from, d.seq, d.broadcast, d.queued_s, d.tx_start_s, d.time_s, d.data);
  };
  for (size_t i = 0; i < a.size(); ++i) EXPECT_EQ(fields(a[i]), fields(b[i])) << i;
  // another seed: other backoffs
  bool differs = a.size() != other.size();
  for (size_t i = 0; !differs && i < a.size(); ++i) differs = fields(a[i]) != fields(other[i]);
  EXPECT_TRUE(differs);
}

TEST(Ns3Radio, TheOrderFramesOfOneStepAreSentInDoesNotMatter) {
  // as lockstep clients do: several senders' frames for the same tick, in any order, some before
  // the gate's step (starting_now false), some after; ns-3 gets them in (time, sender, seq) order
  const std::vector<Eigen::Vector3d> pos{{0, 0, 10}, {5, 0, 10}, {10, 0, 10}, {15, 0, 10}};
  auto deliveries = [&](const std::vector<size_t>& order, bool gate_between) {
    auto ch = channel(Backend::kNs3, pos.size(), {}, 21);
    std::vector<Delivery> out;
    for (int round = 0; round < 10; ++round) {
      const double t = round * 0.05;
      for (size_t k = 0; k < order.size(); ++k) {
        ch->send(order[k], kBroadcast, frame(40, static_cast<uint8_t>(order[k])), t);
        if (gate_between && k == 0) ch->step(t, pos, &out, false);
      }
      for (int s = 0; s < 50; ++s) ch->step(t + s * kStep_s, pos, &out);
    }
    return out;
  };
  const auto a = deliveries({0, 1, 2, 3}, false);
  const auto b = deliveries({3, 1, 0, 2}, true);
  ASSERT_FALSE(a.empty());
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(std::tuple(a[i].to, a[i].from, a[i].seq, a[i].time_s),
              std::tuple(b[i].to, b[i].from, b[i].seq, b[i].time_s))
        << i;
  }
}

TEST(Ns3Radio, AResetStartsOverFromTheSeed) {
  std::vector<Eigen::Vector3d> pos{{0, 0, 10}, {5, 0, 10}, {10, 0, 10}};
  auto ch = channel(Backend::kNs3, 3, {}, 4);
  auto once = [&] {
    return run(*ch, pos, 0.05, [&](double t) {
      if (t == 0.0) {
        for (size_t i = 0; i < 3; ++i) ch->send(i, kBroadcast, frame(30), t);
      }
    });
  };
  const auto first = once();
  ch->reset(4);
  EXPECT_EQ(ch->transmitted(0), 0u);
  const auto second = once();
  ASSERT_EQ(first.size(), second.size());
  for (size_t i = 0; i < first.size(); ++i) EXPECT_EQ(first[i].time_s, second[i].time_s);
}

TEST(Ns3Radio, AKilledHelperFailsTheChannelWithAClearMessage) {
  std::vector<Eigen::Vector3d> pos{{0, 0, 10}, {5, 0, 10}};
  auto ch = make_channel(backend(Backend::kNs3), 2, config_for(Backend::kNs3, {}), 1, kStep_s);
  auto* ns3 = dynamic_cast<Ns3Channel*>(ch.get());
  ASSERT_NE(ns3, nullptr);
  ASSERT_EQ(::kill(ns3->helper_pid(), SIGKILL), 0);
  std::vector<Delivery> out;
  ASSERT_TRUE(ch->send(0, 1, frame(10), 0.0).seq);
  ch->step(0.0, pos, &out);
  EXPECT_NE(ch->failure().find("the ns-3 radio helper failed"), std::string::npos) << ch->failure();
  EXPECT_NE(ch->failure().find("signal 9"), std::string::npos) << ch->failure();
  // nothing more goes through: no silently perfect radio
  EXPECT_FALSE(ch->send(0, 1, frame(10), 0.001).seq);
  ch->step(0.01, pos, &out);
  EXPECT_TRUE(out.empty());
  EXPECT_FALSE(ch->has_due(0.01));
}

TEST(Ns3Radio, AHungHelperFailsTheChannelAfterTheTimeout) {
  std::vector<Eigen::Vector3d> pos{{0, 0, 10}, {5, 0, 10}};
  auto ch = make_channel(backend(Backend::kNs3, 0.5), 2, config_for(Backend::kNs3, {}), 1, kStep_s);
  auto* ns3 = dynamic_cast<Ns3Channel*>(ch.get());
  ASSERT_NE(ns3, nullptr);
  ASSERT_EQ(::kill(ns3->helper_pid(), SIGSTOP), 0);  // alive, never answering
  std::vector<Delivery> out;
  ch->send(0, 1, frame(10), 0.0);
  ch->step(0.0, pos, &out);
  EXPECT_NE(ch->failure().find("no answer in time"), std::string::npos) << ch->failure();
}

TEST(Ns3Radio, ConfigsNs3CannotModelAreRefusedByName) {
  auto ch = channel(Backend::kNs3, 2, {});
  RadioConfig c = ch->config();
  std::string why;
  c.tdma = true;
  c.slot_s = 0.0045;  // holds a 127-byte frame (4.256 ms), not the CCA and turnaround before it
  EXPECT_FALSE(ch->set_config(c, &why));
  EXPECT_NE(why.find("slot_s"), std::string::npos);
  c = ch->config();
  c.loss_probability = 0.2;
  EXPECT_FALSE(ch->set_config(c, &why));
  EXPECT_NE(why.find("loss"), std::string::npos);
  c = ch->config();
  c.propagation = Propagation::kLogDistance;
  c.path_loss_exponent = 3.0;
  EXPECT_TRUE(ch->set_config(c, &why)) << why;
  EXPECT_EQ(ch->config().path_loss_exponent, 3.0);
}

}  // namespace
}  // namespace uavsim::server::radio
