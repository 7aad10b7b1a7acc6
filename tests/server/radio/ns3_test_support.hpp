// What the ns3 backend's tests share (ns3_channel_test.cpp, ns3_tdma_test.cpp): channels of
// either backend configured alike, and a 1 kHz stepping loop with fixed positions.
#pragma once

#include <cmath>
#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include "radio/ns3_channel.hpp"
#include "radio/sim_radio.hpp"

namespace uavsim::server::radio {

inline constexpr double kStep_s = 0.001;  // 1 kHz physics

inline BackendOptions backend(Backend b, double timeout_s = 30.0) {
  BackendOptions o;
  o.backend = b;
  o.ns3.helper_path = UAVSIM_NS3_HELPER_PATH;
  o.ns3.reply_timeout_s = timeout_s;
  return o;
}

// the simple model's collisions on, as close to ns-3's physics as it gets; ns-3's channel is
// configured from the same fields (mac_header_bytes and collisions are fixed there)
inline RadioConfig config_for(Backend b, RadioConfig c = {}) {
  c.mac_header_bytes = 11;
  c.collisions = true;
  (void)b;
  return c;
}

inline std::unique_ptr<RadioChannel> channel(Backend b, size_t n, const RadioConfig& c,
                                             uint64_t seed = 1) {
  return make_channel(backend(b), n, config_for(b, c), seed, kStep_s);
}

// Steps ch at 1 kHz from 0 to end_s, calling on_step(t) before each step (to send frames).
inline std::vector<Delivery> run(RadioChannel& ch, const std::vector<Eigen::Vector3d>& pos,
                                 double end_s, const std::function<void(double)>& on_step) {
  std::vector<Delivery> out;
  const auto steps = static_cast<int64_t>(std::llround(end_s / kStep_s));
  for (int64_t k = 0; k <= steps; ++k) {
    const double t = static_cast<double>(k) * kStep_s;
    on_step(t);
    ch.step(t, pos, &out);
  }
  return out;
}

inline bool every_ms(double t, int period_ms) { return std::llround(t / kStep_s) % period_ms == 0; }

inline std::vector<uint8_t> frame(size_t n, uint8_t fill = 0x5A) {
  return std::vector<uint8_t>(n, fill);
}

// 10 mutually audible senders (on a 5 m grid) broadcast one 50-byte frame each in the same step,
// every 100 ms, 20 rounds: what they delivered, the share of (frame, receiver) pairs that is, and
// the frames CSMA-CA gave up
struct Burst {
  std::vector<Delivery> out;
  double share = 0.0;
  uint64_t access_failures = 0;
};
inline Burst ten_senders_burst(Backend b, uint64_t seed, const RadioConfig& c) {
  constexpr size_t kN = 10;
  constexpr int kRounds = 20;
  std::vector<Eigen::Vector3d> pos;
  for (size_t i = 0; i < kN; ++i) pos.emplace_back(5.0 * (i % 4), 5.0 * (i / 4), 10.0);
  auto ch = channel(b, kN, c, seed);
  int rounds = 0;
  Burst burst;
  burst.out = run(*ch, pos, kRounds * 0.1 + 0.1, [&](double t) {
    if (rounds >= kRounds || !every_ms(t, 100)) return;
    ++rounds;
    for (size_t i = 0; i < kN; ++i) ch->send(i, kBroadcast, frame(50, static_cast<uint8_t>(i)), t);
  });
  burst.share =
      static_cast<double>(burst.out.size()) / static_cast<double>(kRounds * kN * (kN - 1));
  for (size_t i = 0; i < kN; ++i) burst.access_failures += ch->channel_access_failures(i);
  return burst;
}

}  // namespace uavsim::server::radio
