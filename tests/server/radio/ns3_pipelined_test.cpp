// The ns3 backend pipelined (Ns3Channel::set_pipelined, what the server's radio does): the helper
// runs each slice one step ahead, beside the caller's work, and nothing it reports may change but
// the moment the server reads it. Two channels with the same seed, one pipelined and one not, are
// stepped through the same script the way the server steps them (an API gate's call at control
// steps, then the physics step's; vehicles moving; frames sent at the gate and between steps),
// and must give the same deliveries at the same steps and the same counters after every step.
// Needs the helper uavsim-ns3-radio (ctest label ns3).
#include <gtest/gtest.h>
#include <sys/types.h>

#include <csignal>
#include <cstdint>
#include <random>
#include <string>
#include <tuple>
#include <vector>

#include "ns3_test_support.hpp"

namespace uavsim::server::radio {
namespace {

constexpr size_t kVehicles = 8;
constexpr int kControlEvery = 4;  // a control step (and the API gate) every 4 physics steps

// what a channel has after a step: each delivery with the step it came in, and every counter
struct Trace {
  std::vector<std::tuple<int64_t, size_t, size_t, uint64_t, bool, double, double, double,
                         std::vector<uint8_t>>>
      deliveries;
  std::vector<std::vector<uint64_t>> counters;  // per step: every link's and vehicle's counters
};

std::vector<uint64_t> counters(const RadioChannel& ch) {
  std::vector<uint64_t> c;
  for (size_t a = 0; a < kVehicles; ++a) {
    for (size_t b = 0; b < kVehicles; ++b) {
      if (a == b) continue;
      const LinkStats& s = ch.link(a, b);
      c.insert(c.end(), {s.sent, s.delivered, s.lost, s.collided, s.out_of_range, s.no_ack});
    }
    c.insert(c.end(), {ch.transmitted(a), ch.queued(a), ch.channel_access_failures(a)});
  }
  return c;
}

// vehicles on circles of different radii and speeds, so links cross the edge of range
std::vector<Eigen::Vector3d> positions_at(double t, std::vector<Eigen::Vector3d>* velocities) {
  std::vector<Eigen::Vector3d> p(kVehicles);
  velocities->assign(kVehicles, Eigen::Vector3d::Zero());
  for (size_t i = 0; i < kVehicles; ++i) {
    const double r = 20.0 + 15.0 * static_cast<double>(i);
    const double w = 0.5 + 0.1 * static_cast<double>(i);
    p[i] = {r * std::cos(w * t), r * std::sin(w * t), 10.0 + static_cast<double>(i)};
    (*velocities)[i] = {-r * w * std::sin(w * t), r * w * std::cos(w * t), 0.0};
  }
  return p;
}

// The script: steps to end_s; at control steps the gate's call (starting_now false) comes first
// and frames follow it (what lockstep clients send for the tick); other frames come between
// steps. Broadcasts and unicasts of seeded sizes from seeded senders.
Trace run_script(const RadioConfig& config, bool pipelined, double end_s, double send_prob) {
  auto ch = channel(Backend::kNs3, kVehicles, config, 7);
  ch->set_pipelined(pipelined);
  std::mt19937_64 rng(42);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const size_t max_bytes = ch->max_payload_bytes() < 200 ? ch->max_payload_bytes() : 200;
  auto send_some = [&](double t) {
    for (size_t from = 0; from < kVehicles; ++from) {
      if (u(rng) >= send_prob) continue;
      const int to = u(rng) < 0.7
                         ? kBroadcast
                         : static_cast<int>((from + 1 + rng() % (kVehicles - 1)) % kVehicles);
      const size_t n = 1 + rng() % max_bytes;
      ch->send(from, to, frame(n, static_cast<uint8_t>(from)), t);
    }
  };
  Trace trace;
  std::vector<Eigen::Vector3d> vel;
  const auto steps = static_cast<int64_t>(std::llround(end_s / kStep_s));
  double t = 0.0;
  for (int64_t k = 0; k <= steps; ++k, t += kStep_s) {  // the sim's clock: MuJoCo adds each step
    const std::vector<Eigen::Vector3d> pos = positions_at(t, &vel);
    std::vector<Delivery> out;
    ch->set_velocities(vel);
    if (k % kControlEvery == 0) {
      ch->step(t, pos, &out, false);
      send_some(t);
    } else if (u(rng) < 0.3) {
      send_some(t);
    }
    ch->step(t, pos, &out, true);
    for (Delivery& d : out) {
      trace.deliveries.emplace_back(k, d.to, d.from, d.seq, d.broadcast, d.queued_s, d.tx_start_s,
                                    d.time_s, std::move(d.data));
    }
    trace.counters.push_back(counters(*ch));
    EXPECT_EQ(ch->failure(), "");
  }
  return trace;
}

void expect_same(const RadioConfig& config, double end_s, double send_prob) {
  const Trace plain = run_script(config, false, end_s, send_prob);
  const Trace ahead = run_script(config, true, end_s, send_prob);
  ASSERT_GT(plain.deliveries.size(), 50u);  // the script exercises the channel
  EXPECT_EQ(ahead.deliveries.size(), plain.deliveries.size());
  EXPECT_TRUE(ahead.deliveries == plain.deliveries);
  ASSERT_EQ(ahead.counters.size(), plain.counters.size());
  for (size_t k = 0; k < plain.counters.size(); ++k) {
    ASSERT_EQ(ahead.counters[k], plain.counters[k]) << "counters differ after step " << k;
  }
}

RadioConfig log_distance(RadioConfig c = {}) {
  c.propagation = Propagation::kLogDistance;
  c.shadowing_sigma_db = 4.0;
  c.sensitivity_dbm = -92.0;
  return c;
}

TEST(Ns3Pipelined, CsmaCaOn802154GivesTheSameDeliveriesAtTheSameSteps) {
  // contention, retries, links at the edge of range, quiet times between frames
  expect_same(config_for(Backend::kNs3, log_distance()), 1.5, 0.08);
}

TEST(Ns3Pipelined, TdmaOn802154GivesTheSameDeliveriesAtTheSameSteps) {
  RadioConfig c = log_distance();
  c.tdma = true;
  c.slot_s = 0.005;
  c.period_s = 0.05;
  expect_same(config_for(Backend::kNs3, c), 1.5, 0.05);
}

TEST(Ns3Pipelined, On80211WithTheSendSpreadGivesTheSameDeliveriesAtTheSameSteps) {
  RadioConfig c = log_distance();
  c.technology = Technology::k80211;
  c.send_spread_s = 0.004;
  expect_same(config_for(Backend::kNs3, c), 1.0, 0.15);
}

TEST(Ns3Pipelined, AHelperThatDiesWhileAStepIsOutIsReportedAndNothingHangs) {
  auto ch = channel(Backend::kNs3, 2, RadioConfig{}, 1);
  ch->set_pipelined(true);
  const std::vector<Eigen::Vector3d> pos{{0, 0, 10}, {10, 0, 10}};
  std::vector<Delivery> out;
  ch->send(0, kBroadcast, frame(50), 0.0);
  ch->step(0.0, pos, &out);  // sent with a run ahead to 1 ms, its answer not yet read
  ::kill(static_cast<Ns3Channel&>(*ch).helper_pid(), SIGKILL);
  for (int k = 1; k <= 3; ++k) ch->step(k * kStep_s, pos, &out);
  EXPECT_NE(ch->failure().find("the ns-3 radio helper failed"), std::string::npos) << ch->failure();
  EXPECT_EQ(ch->send(0, kBroadcast, frame(50), 0.004).error, Error::kQueueFull);
}

}  // namespace
}  // namespace uavsim::server::radio
