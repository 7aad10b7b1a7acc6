#include "radio/radio_model.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <tuple>
#include <vector>

namespace uavsim::server::radio {
namespace {

constexpr double kStep_s = 0.001;  // 1 kHz physics
constexpr double kSigmas = 5.0;    // binomial tolerance: a 5-sigma miss happens ~6e-7 of the time
constexpr double kTimeTol_s = 1e-9;
constexpr double kAirtimeTol_s = 1e-12;
constexpr double kSlotIndexTol = 1e-6;
constexpr double kFrameCountTol = 2.0;

// |k - n p| <= kSigmas * sqrt(n p (1 - p))
void expect_binomial(uint64_t k, uint64_t n, double p, const char* what) {
  const double sd = std::sqrt(static_cast<double>(n) * p * (1.0 - p));
  EXPECT_LE(std::abs(static_cast<double>(k) - static_cast<double>(n) * p), kSigmas * sd)
      << what << ": " << k << " of " << n << ", expected p = " << p;
}

std::vector<uint8_t> bytes(size_t n, uint8_t fill = 0xAB) { return std::vector<uint8_t>(n, fill); }

// Steps the model from time t to end_s, calling on_step(t) before each step (to send frames).
template <class F>
std::vector<Delivery> run(RadioModel& m, const std::vector<Eigen::Vector3d>& pos, double end_s,
                          F on_step, double start_s = 0.0) {
  std::vector<Delivery> out;
  const auto steps = static_cast<int64_t>(std::llround((end_s - start_s) / kStep_s));
  for (int64_t k = 0; k <= steps; ++k) {
    const double t = start_s + static_cast<double>(k) * kStep_s;
    on_step(t);
    m.step(t, pos, &out);
  }
  return out;
}

std::vector<Eigen::Vector3d> line(std::initializer_list<double> xs) {
  std::vector<Eigen::Vector3d> p;
  for (double x : xs) p.emplace_back(x, 0.0, 10.0);
  return p;
}

TEST(RadioModel, AirtimeOfAFullFrameAt250kbps) {
  // (127 + 6 PHY header bytes) * 8 bits / 250 kbit/s = 4.256 ms
  EXPECT_NEAR(airtime_s(127), 0.004256, kAirtimeTol_s);
}

TEST(RadioModel, BroadcastDeliveryRateMatchesTheLossProbability) {
  RadioConfig c;
  c.loss_probability = 0.3;
  RadioModel m(3, c, 42, kStep_s);
  const auto pos = line({0.0, 50.0, 90.0});
  constexpr int kFrames = 20000;
  int sent = 0;
  // one 20-byte frame every 10 ms: no queueing, no overlap
  auto out = run(m, pos, kFrames * 0.01 + 0.05, [&](double t) {
    if (sent < kFrames && std::llround(t / kStep_s) % 10 == 0) {
      ASSERT_TRUE(m.send(0, kBroadcast, bytes(20), t).seq);
      ++sent;
    }
  });
  for (size_t r : {1u, 2u}) {
    const LinkStats& s = m.link(0, r);
    EXPECT_EQ(s.sent, static_cast<uint64_t>(kFrames));
    EXPECT_EQ(s.delivered + s.lost, s.sent);
    EXPECT_EQ(s.collided + s.out_of_range, 0u);
    expect_binomial(s.delivered, s.sent, 1.0 - c.loss_probability, "delivered");
  }
  EXPECT_EQ(out.size(), m.link(0, 1).delivered + m.link(0, 2).delivered);
}

// The API's gate steps the model (starting_now = false) between the requests of lockstep clients,
// which come in any order: frames sent at a time go on air together at the step after the gate,
// so the seeded loss draws are the same whichever client's frame came first.
TEST(RadioModel, LossDrawsDoNotDependOnTheOrderFramesWereSentInWithinATime) {
  RadioConfig c;
  c.loss_probability = 0.5;
  const auto pos = line({0.0, 10.0, 20.0});
  auto fly = [&](bool zero_first) {
    RadioModel m(3, c, 42, kStep_s);
    std::vector<Delivery> out;
    for (int k = 0; k < 200; ++k) {
      const double t = k * 0.05;
      for (int i = 0; i < 2; ++i) {
        const size_t from = (i == 0) == zero_first ? 0 : 1;
        EXPECT_TRUE(m.send(from, kBroadcast, bytes(40, static_cast<uint8_t>(from)), t).seq);
        m.step(t, pos, &out, /*starting_now=*/false);  // the gate, between two clients' requests
      }
      for (int s = 0; s < 50; ++s)
        m.step(t + s * kStep_s, pos, &out);  // the steps to the next tick
    }
    std::vector<std::tuple<size_t, size_t, uint64_t>> seen;
    for (const Delivery& d : out) seen.emplace_back(d.to, d.from, d.seq);
    return seen;
  };
  const auto a = fly(true), b = fly(false);
  EXPECT_GT(a.size(), 100u);
  EXPECT_LT(a.size(), 700u);  // 400 frames x 2 receivers, about half lost
  EXPECT_EQ(a, b);
}

TEST(RadioModel, FramesNeverReachAVehicleOutOfRange) {
  RadioConfig c;
  c.range_m = 100.0;
  RadioModel m(3, c, 7, kStep_s);
  auto pos = line({0.0, 99.0, 101.0});
  int sent = 0;
  std::vector<Delivery> out = run(m, pos, 2.0, [&](double t) {
    if (t < 1.9 && std::llround(t / kStep_s) % 20 == 0) {  // the last ones resolved before the end
      EXPECT_TRUE(m.send(0, kBroadcast, bytes(30), t).seq);
      EXPECT_TRUE(m.send(1, 2, bytes(30), t).seq);  // 2 m apart: in range
      ++sent;
    }
  });
  for (const Delivery& d : out)
    EXPECT_FALSE(d.from == 0 && d.to == 2) << "frame " << d.seq << " at " << d.time_s;
  EXPECT_EQ(m.link(0, 2).delivered, 0u);
  EXPECT_EQ(m.link(0, 2).out_of_range, m.link(0, 2).sent);
  EXPECT_EQ(m.link(0, 1).delivered, m.link(0, 1).sent);
  EXPECT_GT(m.link(1, 2).delivered, 0u);
}

TEST(RadioModel, AVehicleFlyingOutOfRangeStopsReceivingAtTheRangeBoundary) {
  RadioConfig c;
  c.range_m = 100.0;
  RadioModel m(2, c, 7, kStep_s);
  std::vector<Eigen::Vector3d> pos = line({0.0, 0.0});
  std::vector<Delivery> out;
  // vehicle 1 flies away at 50 m/s: out of range after t = 2 s
  for (int k = 0; k <= 4000; ++k) {
    const double t = k * kStep_s;
    pos[1].x() = 50.0 * t;
    if (k % 10 == 0) m.send(0, 1, bytes(10), t);
    m.step(t, pos, &out);
  }
  ASSERT_FALSE(out.empty());
  for (const Delivery& d : out) EXPECT_LE(d.tx_start_s, 2.0 + kStep_s);
  EXPECT_GT(out.back().tx_start_s, 2.0 - 0.02);
  EXPECT_GT(m.link(0, 1).out_of_range, 150u);
}

TEST(RadioModel, LogDistanceDeliveryFollowsTheShadowingDistribution) {
  RadioConfig c;
  c.propagation = Propagation::kLogDistance;
  // margin = tx - sens - PL(1 m) - 10 n log10(d); P(received) = P(X_sigma <= margin) = Phi(margin /
  // sigma) vehicle 1 at margin 0 (p = 0.5), vehicle 2 at margin +sigma (p = Phi(1) = 0.8413),
  // vehicle 3 at 10 km (margin -55 dB = -13.8 sigma: never)
  const double budget_db = c.tx_power_dbm - c.sensitivity_dbm - c.reference_loss_db;
  const double d_half_m = std::pow(10.0, budget_db / (10.0 * c.path_loss_exponent));
  const double d_sigma_m =
      std::pow(10.0, (budget_db - c.shadowing_sigma_db) / (10.0 * c.path_loss_exponent));
  RadioModel m(4, c, 99, kStep_s);
  const auto pos = line({0.0, d_half_m, -d_sigma_m, 10000.0});
  constexpr int kFrames = 10000;
  int sent = 0;
  run(m, pos, kFrames * 0.01 + 0.05, [&](double t) {
    if (sent < kFrames && std::llround(t / kStep_s) % 10 == 0) {
      m.send(0, kBroadcast, bytes(10), t);
      ++sent;
    }
  });
  expect_binomial(m.link(0, 1).delivered, m.link(0, 1).sent, 0.5, "at the 50% distance");
  expect_binomial(m.link(0, 2).delivered, m.link(0, 2).sent, 0.5 * std::erfc(-1.0 / std::sqrt(2.0)),
                  "one sigma inside");
  EXPECT_EQ(m.link(0, 3).delivered, 0u);
  EXPECT_EQ(m.link(0, 3).out_of_range, static_cast<uint64_t>(kFrames));
}

TEST(RadioModel, UnicastReachesOnlyTheAddressee) {
  RadioModel m(3, RadioConfig{}, 1, kStep_s);
  const auto pos = line({0.0, 10.0, 20.0});
  auto out = run(m, pos, 0.1, [&](double t) {
    if (t == 0.0) m.send(0, 2, {1, 2, 3}, t);
  });
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].to, 2u);
  EXPECT_EQ(out[0].from, 0u);
  EXPECT_FALSE(out[0].broadcast);
  EXPECT_EQ(out[0].data, (std::vector<uint8_t>{1, 2, 3}));
  EXPECT_EQ(m.link(0, 1).sent, 0u);
}

TEST(RadioModel, LatencyIsAtLeastOneStepAndAddsTheConfiguredDelay) {
  RadioConfig c;
  RadioModel m(2, c, 1, kStep_s);
  const auto pos = line({0.0, 10.0});
  // 1-byte frame: airtime 7 * 8 / 250000 = 0.224 ms < one step, so the step is the bound
  auto out = run(m, pos, 0.1, [&](double t) {
    if (std::abs(t - 0.010) < kTimeTol_s) m.send(0, 1, {7}, t);
  });
  ASSERT_EQ(out.size(), 1u);
  EXPECT_NEAR(out[0].time_s - out[0].queued_s, kStep_s, kTimeTol_s);

  c.latency_s = 0.05;
  RadioModel slow(2, c, 1, kStep_s);
  out = run(slow, pos, 0.2, [&](double t) {
    if (std::abs(t - 0.010) < kTimeTol_s) slow.send(0, 1, bytes(127), t);
  });
  ASSERT_EQ(out.size(), 1u);
  EXPECT_NEAR(out[0].time_s, 0.010 + airtime_s(127) + 0.05, kTimeTol_s);
}

TEST(RadioModel, OverlappingTransmissionsCollideWithoutTdma) {
  RadioConfig c;
  c.collisions = true;
  RadioModel m(3, c, 1, kStep_s);
  const auto pos = line({0.0, 20.0, 40.0});
  // vehicles 0 and 2 send 100-byte frames (3.4 ms on air) 1 ms apart: vehicle 1 hears both overlap
  auto out = run(m, pos, 0.1, [&](double t) {
    if (std::abs(t - 0.010) < kTimeTol_s) m.send(0, 1, bytes(100), t);
    if (std::abs(t - 0.011) < kTimeTol_s) m.send(2, 1, bytes(100), t);
    // later, 10 ms apart: no overlap
    if (std::abs(t - 0.050) < kTimeTol_s) m.send(0, 1, bytes(100), t);
    if (std::abs(t - 0.060) < kTimeTol_s) m.send(2, 1, bytes(100), t);
  });
  EXPECT_EQ(m.link(0, 1).collided, 1u);
  EXPECT_EQ(m.link(2, 1).collided, 1u);
  EXPECT_EQ(m.link(0, 1).delivered, 1u);
  EXPECT_EQ(m.link(2, 1).delivered, 1u);
  ASSERT_EQ(out.size(), 2u);
  EXPECT_GE(out[0].queued_s, 0.05 - kTimeTol_s);

  // the same traffic without collision modelling: everything arrives
  RadioModel ideal(3, RadioConfig{}, 1, kStep_s);
  out = run(ideal, pos, 0.1, [&](double t) {
    if (std::abs(t - 0.010) < kTimeTol_s) ideal.send(0, 1, bytes(100), t);
    if (std::abs(t - 0.011) < kTimeTol_s) ideal.send(2, 1, bytes(100), t);
  });
  EXPECT_EQ(out.size(), 2u);
}

TEST(RadioModel, AVehicleCannotReceiveWhileItTransmits) {
  RadioConfig c;
  c.collisions = true;
  RadioModel m(2, c, 1, kStep_s);
  const auto pos = line({0.0, 20.0});
  run(m, pos, 0.1, [&](double t) {
    if (std::abs(t - 0.010) < kTimeTol_s) {
      m.send(0, 1, bytes(100), t);
      m.send(1, 0, bytes(100), t);
    }
  });
  EXPECT_EQ(m.link(0, 1).collided, 1u);
  EXPECT_EQ(m.link(1, 0).collided, 1u);
}

TEST(RadioModel, ASendersFramesGoOutOneAfterAnother) {
  RadioConfig c;
  c.collisions = true;
  RadioModel m(2, c, 1, kStep_s);
  const auto pos = line({0.0, 20.0});
  auto out = run(m, pos, 0.2, [&](double t) {
    if (t == 0.0) {
      for (int k = 0; k < 10; ++k) m.send(0, 1, bytes(127), t);
    }
  });
  ASSERT_EQ(out.size(), 10u);  // its own frames never overlap one another
  for (size_t k = 0; k < out.size(); ++k)
    EXPECT_NEAR(out[k].tx_start_s, k * airtime_s(127), kTimeTol_s);
}

// N vehicles, all in range, each sending random-length frames at seeded random times with at most
// one of its frames outstanding (queued or on air) when it sends the next.
struct TdmaRun {
  std::vector<Delivery> out;
  double max_latency_s = 0.0;
  uint64_t collided = 0;
  uint64_t sent = 0;
};
TdmaRun run_tdma(size_t n, double slot_s, double period_s, double seconds) {
  RadioConfig c;
  c.tdma = true;
  c.slot_s = slot_s;
  c.period_s = period_s;
  c.collisions = true;  // on, to prove TDMA never lets two transmissions overlap
  RadioModel m(n, c, 5, kStep_s);
  std::vector<Eigen::Vector3d> pos;
  for (size_t i = 0; i < n; ++i) pos.emplace_back(5.0 * i, 0.0, 10.0);
  std::mt19937_64 rng(11);
  std::vector<double> next_send_s(n);
  std::vector<bool> outstanding(n, false);
  std::vector<uint64_t> seq(n, 0);
  for (double& t : next_send_s) t = std::uniform_real_distribution<double>(0.0, period_s)(rng);
  TdmaRun r;
  const auto steps = static_cast<int64_t>(std::llround(seconds / kStep_s));
  for (int64_t k = 0; k <= steps; ++k) {
    const double t = k * kStep_s;
    for (size_t i = 0; i < n; ++i) {
      if (outstanding[i] || t < next_send_s[i]) continue;
      const size_t len = 1 + rng() % kMaxFrameBytes;
      seq[i] = *m.send(i, kBroadcast, bytes(len), t).seq;
      outstanding[i] = true;
    }
    const size_t before = r.out.size();
    m.step(t, pos, &r.out);
    for (size_t d = before; d < r.out.size(); ++d) {
      const Delivery& x = r.out[d];
      r.max_latency_s = std::max(r.max_latency_s, x.time_s - x.queued_s);
      // its own slot: (start mod T) / D is a whole slot index k with k mod N = sender
      const double in_period = std::fmod(x.tx_start_s + kTimeTol_s, period_s) - kTimeTol_s;
      const double slot = in_period / slot_s;
      EXPECT_NEAR(slot, std::round(slot), kSlotIndexTol) << "not at a slot start: " << x.tx_start_s;
      EXPECT_EQ(static_cast<size_t>(std::llround(slot)) % n, x.from) << "in another vehicle's slot";
      EXPECT_LE(x.tx_start_s + airtime_s(x.data.size()), x.tx_start_s + slot_s + kTimeTol_s);
      if (x.seq == seq[x.from] && outstanding[x.from]) {
        outstanding[x.from] = false;
        next_send_s[x.from] = t + std::uniform_real_distribution<double>(0.0, period_s)(rng);
      }
    }
  }
  for (size_t a = 0; a < n; ++a) {
    for (size_t b = 0; b < n; ++b) {
      r.collided += m.link(a, b).collided;
      r.sent += m.link(a, b).sent;
    }
  }
  return r;
}

TEST(RadioModel, TdmaNeverCollidesAndBoundsLatencyByTwoNd) {
  // seed 6.2 worst case: D does not divide T and T / (N D) is not whole (T = 1, D = 0.03, N = 7:
  // 33 slots, 10 ms wasted, the last subsequence truncated)
  constexpr size_t kN = 7;
  constexpr double kSlot_s = 0.03;
  const TdmaRun r = run_tdma(kN, kSlot_s, 1.0, 60.0);
  EXPECT_GT(r.sent, 1000u);
  EXPECT_EQ(r.collided, 0u);
  EXPECT_LE(r.max_latency_s, 2.0 * kN * kSlot_s + kTimeTol_s);
  // the bound is not vacuous: the truncated subsequence makes some waits longer than N D
  EXPECT_GT(r.max_latency_s, kN * kSlot_s);
}

TEST(RadioModel, TdmaWithWholeSubsequences) {
  constexpr size_t kN = 10;
  constexpr double kSlot_s = 0.005;  // 4.256 ms frame fits; 20 slots in T = 0.1
  const TdmaRun r = run_tdma(kN, kSlot_s, 0.1, 20.0);
  EXPECT_GT(r.sent, 1000u);
  EXPECT_EQ(r.collided, 0u);
  EXPECT_LE(r.max_latency_s, 2.0 * kN * kSlot_s + kTimeTol_s);
}

TEST(RadioModel, WithoutTdmaTheSameTrafficCollides) {
  // the control for the TDMA tests: random traffic, collisions on, no slots
  RadioConfig c;
  c.collisions = true;
  RadioModel m(7, c, 5, kStep_s);
  std::vector<Eigen::Vector3d> pos;
  for (size_t i = 0; i < 7; ++i) pos.emplace_back(5.0 * i, 0.0, 10.0);
  std::mt19937_64 rng(3);
  run(m, pos, 30.0, [&](double t) {
    for (size_t i = 0; i < 7; ++i) {
      if (rng() % 200 == 0) m.send(i, kBroadcast, bytes(100), t);
    }
  });
  uint64_t collided = 0;
  for (size_t a = 0; a < 7; ++a) {
    for (size_t b = 0; b < 7; ++b) collided += m.link(a, b).collided;
  }
  EXPECT_GT(collided, 100u);
}

TEST(RadioModel, SameSeedSameDeliveries) {
  auto deliveries = [](uint64_t seed) {
    RadioConfig c;
    c.propagation = Propagation::kLogDistance;
    c.loss_probability = 0.2;
    c.collisions = true;
    RadioModel m(5, c, seed, kStep_s);
    std::vector<Eigen::Vector3d> pos;
    for (size_t i = 0; i < 5; ++i) pos.emplace_back(30.0 * i, 0.0, 10.0);
    std::mt19937_64 traffic(1);  // the same inputs every run
    std::vector<std::tuple<size_t, size_t, uint64_t, double>> log;
    for (const Delivery& d : run(m, pos, 5.0, [&](double t) {
           for (size_t i = 0; i < 5; ++i) {
             if (traffic() % 50 == 0) m.send(i, kBroadcast, bytes(40), t);
           }
         })) {
      log.emplace_back(d.to, d.from, d.seq, d.time_s);
    }
    return log;
  };
  const auto a = deliveries(123);
  EXPECT_GT(a.size(), 500u);
  EXPECT_EQ(a, deliveries(123));
  EXPECT_NE(a, deliveries(124));
}

TEST(RadioModel, ResetRestartsTheSameRun) {
  RadioConfig c;
  c.loss_probability = 0.5;
  RadioModel m(2, c, 9, kStep_s);
  const auto pos = line({0.0, 10.0});
  auto traffic = [&](double t) {
    if (std::llround(t / kStep_s) % 5 == 0) m.send(0, 1, bytes(8), t);
  };
  const auto first = run(m, pos, 1.0, traffic);
  m.reset(9);
  const auto second = run(m, pos, 1.0, traffic);
  ASSERT_EQ(first.size(), second.size());
  for (size_t k = 0; k < first.size(); ++k) EXPECT_EQ(first[k].seq, second[k].seq);
}

TEST(RadioModel, BadFramesAndDestinationsAreRefused) {
  RadioConfig c;
  c.max_queue_frames = 2;
  RadioModel m(2, c, 1, kStep_s);
  EXPECT_EQ(m.send(0, 1, bytes(128), 0.0).error, Error::kFrameTooLarge);
  EXPECT_EQ(m.send(0, 1, {}, 0.0).error, Error::kEmptyFrame);
  EXPECT_EQ(m.send(2, 1, bytes(1), 0.0).error, Error::kUnknownVehicle);
  EXPECT_EQ(m.send(0, 5, bytes(1), 0.0).error, Error::kUnknownVehicle);
  EXPECT_EQ(m.send(1, 1, bytes(1), 0.0).error, Error::kBadDestination);
  EXPECT_TRUE(m.send(0, 1, bytes(127), 0.0).seq);
  EXPECT_TRUE(m.send(0, 1, bytes(127), 0.0).seq);
  EXPECT_EQ(m.send(0, 1, bytes(1), 0.0).error, Error::kQueueFull);
}

// issue 29: one sender offering 7000 frames a second to a channel that carries 1420 of them. The
// frames it cannot carry are refused at send() once max_queue_frames wait to go on air, instead of
// piling up (22000 after 4 s before, each step sorting them all); what it accepts goes out at the
// channel's rate, and another sender's frames are not held up by the flood.
TEST(RadioModel, AFloodingSenderIsRefusedPastItsBacklogAndTheOthersStillGoOnAir) {
  RadioConfig c;  // max_queue_frames 256, no collisions
  RadioModel m(3, c, 1, kStep_s);
  // 16 bytes: (16 + 6) * 8 / 250000 = 0.704 ms on air, 1420 frames a second at most
  const double airtime = airtime_s(16);
  int accepted = 0, refused = 0, other_sent = 0;
  size_t most_waiting = 0;
  const auto out = run(m, line({0.0, 10.0, 20.0}), 1.0, [&](double t) {
    for (int f = 0; f < 7; ++f) {
      const SendResult r = m.send(0, kBroadcast, bytes(16), t);
      if (r.seq) {
        ++accepted;
      } else {
        EXPECT_EQ(r.error, Error::kQueueFull);
        ++refused;
      }
    }
    most_waiting = std::max(most_waiting, m.queued(0));
    if (std::llround(t / kStep_s) % 10 == 0 && t < 0.995) {
      ASSERT_TRUE(m.send(1, 2, bytes(16), t).seq);  // 100 a second, delivered by the end
      ++other_sent;
    }
  });
  EXPECT_EQ(accepted + refused, 7 * 1001);
  EXPECT_LE(most_waiting, c.max_queue_frames);
  // what was accepted is what went on air plus what still waits, and it went at the channel's
  // rate: every frame back to back from the first step on
  EXPECT_EQ(m.transmitted(0) + m.queued(0), static_cast<uint64_t>(accepted));
  EXPECT_NEAR(static_cast<double>(m.transmitted(0)), std::ceil(1.0 / airtime), kFrameCountTol);
  // still flooding at the end: the backlog full but for the frames of the last step's airtime
  EXPECT_GE(m.queued(0) + 2, c.max_queue_frames);
  int from_other = 0;
  for (const Delivery& d : out) from_other += d.from == 1 ? 1 : 0;
  EXPECT_EQ(from_other, other_sent);  // every one of them, none held behind the flood
}

TEST(RadioModel, UnusableConfigsAreNamed) {
  RadioConfig c;
  c.tdma = true;
  c.slot_s = 0.004;  // shorter than a 127-byte frame
  EXPECT_NE(validate(c, 3).find("slot_s"), std::string::npos);
  c.slot_s = 0.3;
  EXPECT_NE(validate(c, 4).find("period_s"), std::string::npos);  // 4 * 0.3 > 1
  EXPECT_EQ(validate(c, 3), "");
  c.loss_probability = 1.5;
  EXPECT_NE(validate(c, 3).find("loss_probability"), std::string::npos);
  EXPECT_THROW(RadioModel(3, c, 1, kStep_s), std::invalid_argument);
}

}  // namespace
}  // namespace uavsim::server::radio
