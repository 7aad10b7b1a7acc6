// The A2A radio model (seed 6.2): every vehicle has an IEEE 802.15.4 transceiver that sends
// broadcast or unicast frames of at most 127 bytes to the vehicles in range. Pure: no MuJoCo, no
// sockets, no clock — the caller steps it in sim time with the vehicles' positions at that time.
//
// A frame's life:
//   queued (send) -> scheduled (its transmission start: at once, after the vehicle's previous
//   frame, or at the vehicle's next TDMA slot) -> on air (at the first step at or after its start:
//   the positions of that step decide who is in range, and the seeded loss draws are made) ->
//   resolved (at the first step at or after its end: overlapping transmissions heard at a receiver
//   collide) -> delivered at max(end + latency_s, queued + one step).
// Determinism: every random draw happens in a fixed order — transmissions by (start, sender, seq),
// then receivers by index — from one seeded generator, so the same seed and inputs give the same
// deliveries.
//
// TDMA (seed 6.2, fig. 6.2): the GPS period T is cut into slots of duration D; slot k belongs to
// vehicle k mod N, slots that do not fit whole in T are wasted; a vehicle transmits one frame per
// own slot, at the slot's start. With D >= the longest frame's airtime no two transmissions
// overlap, and a frame queued with an empty queue waits less than 2·N·D.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "radio/radio_channel.hpp"

namespace uavsim::server::radio {

// The range of every number a RadioConfig accepts (validate() refuses the rest with bad_field's
// message): physical values with room to spare, so that a huge, negative or denormal number from
// the API or a world never reaches the propagation maths or the slot arithmetic.
inline constexpr double kMinRangeM = 0.1;
inline constexpr double kMaxRangeM = 1e6;
inline constexpr double kMinTxPowerDbm = -50.0;       // below any real transceiver
inline constexpr double kMaxTxPowerDbm = 60.0;        // 1 kW
inline constexpr double kMinSensitivityDbm = -174.0;  // the thermal noise floor in 1 Hz
inline constexpr double kMaxSensitivityDbm = 0.0;
inline constexpr double kMaxLossDb = 300.0;
inline constexpr double kMinPathLossExponent = 1.0;   // waveguide-like corridors go below 2
inline constexpr double kMaxPathLossExponent = 10.0;  // dense obstruction stays under 6
inline constexpr double kMaxShadowingSigmaDb = 30.0;
inline constexpr double kMaxLatencyS = 3600.0;
inline constexpr double kMaxPeriodS = 3600.0;   // TDMA period T
inline constexpr double kMaxSendSpreadS = 1.0;  // a program's tick is well under a second

// Why a config is unusable for vehicles vehicles ("" if usable); names the field.
std::string validate(const RadioConfig& config, size_t vehicles);

// The start of vehicle's first TDMA slot at or after t_s with config's slot_s and period_s shared
// by vehicles vehicles (exact slot arithmetic, seed fig. 6.2; config as validate() accepts it).
// Both backends schedule with it, so a frame starts in the same slot on either.
double tdma_slot_start_s(const RadioConfig& config, size_t vehicles, size_t vehicle, double t_s);

class RadioModel : public RadioChannel {
 public:
  // step_s: the caller's step (the physics step), the least latency. Throws std::invalid_argument
  // with validate()'s message for an unusable config (a startup error).
  RadioModel(size_t vehicles, const RadioConfig& config, uint64_t seed, double step_s);

  // Queues a frame from vehicle from to vehicle to (or kBroadcast) at time now_s. Not thread-safe
  // (one caller: the loop thread).
  SendResult send(size_t from, int to, const std::vector<uint8_t>& data, double now_s) override;

  // Advances to now_s (non-decreasing) with every vehicle's position at now_s: schedules queued
  // frames, puts due ones on air, resolves finished ones and appends the frames arriving at or
  // before now_s to *out, ordered by (arrival, receiver, sender, seq). Calling it again at the same
  // time only handles frames queued since. With starting_now false, frames that start at now_s
  // stay off air (their positions and loss draws wait for a later call at now_s): a caller that
  // may still receive frames for now_s (the API's gate, while lockstep clients are working on the
  // tick) keeps the draws in (start, sender, seq) order whatever order the frames came in.
  void step(double now_s, const std::vector<Eigen::Vector3d>& positions_enu_m,
            std::vector<Delivery>* out, bool starting_now = true) override;

  // True when step(now_s) would put a frame on air (so the caller needs fresh positions).
  bool has_due(double now_s) const override;

  // Replaces the config; frames already scheduled keep their start. False (and *error) if unusable.
  bool set_config(const RadioConfig& config, std::string* error) override;
  const RadioConfig& config() const override { return config_; }
  // Drops every frame and counter and restarts the generator from seed.
  void reset(uint64_t seed) override;

  size_t vehicle_count() const override { return vehicles_; }
  const LinkStats& link(size_t from, size_t to) const override {
    return links_[from * vehicles_ + to];
  }
  uint64_t transmitted(size_t vehicle) const override { return transmitted_[vehicle]; }
  // Frames of vehicle that send() accepted and that are not on air yet (waiting for the sender's
  // previous frames or its slot): what max_queue_frames bounds.
  size_t queued(size_t vehicle) const override { return backlog_[vehicle]; }
  const char* backend_name() const override { return "simple"; }
  size_t max_payload_bytes() const override { return kMaxFrameBytes - config_.mac_header_bytes; }

  // The start of vehicle's first TDMA slot at or after t_s (exact slot arithmetic, seed fig. 6.2).
  double next_slot_start_s(size_t vehicle, double t_s) const;

  // validate(), and the technology this model has (802.15.4).
  static std::string validate_simple(const RadioConfig& config, size_t vehicles);

 private:
  struct Frame {
    size_t from = 0;
    int to = kBroadcast;
    uint64_t seq = 0;
    double queued_s = 0.0;
    double start_s = 0.0;
    double end_s = 0.0;
    std::vector<uint8_t> data;
    // on air: per receiver, heard (in range) and the loss draw
    std::vector<uint8_t> heard;
    std::vector<uint8_t> dropped;
    bool resolved = false;
  };

  bool reaches(size_t from, size_t to, const Eigen::Vector3d& a, const Eigen::Vector3d& b);
  double uniform();
  double normal();
  void go_on_air(Frame& f, const std::vector<Eigen::Vector3d>& positions);
  void resolve(const Frame& f, std::vector<Delivery>* arrivals);

  size_t vehicles_;
  RadioConfig config_;
  double step_s_;
  std::mt19937_64 rng_;
  std::vector<std::deque<Frame>> queues_;  // per sender, FIFO, not yet scheduled
  std::vector<uint64_t> next_seq_;
  std::vector<double> busy_until_s_;  // per sender: end of its last scheduled transmission
  std::vector<Frame> scheduled_;      // sorted by (start, from, seq), not yet on air
  std::vector<Frame> air_;            // on air or recently ended, for overlap checks
  std::vector<Delivery> pending_;     // resolved, not yet arrived
  std::vector<LinkStats> links_;      // from * N + to
  std::vector<uint64_t> transmitted_;
  // per sender: accepted, not yet on air (in queues_ or scheduled_). send() refuses a frame past
  // max_queue_frames of them: a sender offering more than its airtime carries is told at once
  // (queue_full) instead of growing scheduled_ without end (issue 29: 7000 frames a second from
  // one client, 1420 carried, left a backlog of 22000 frames after 4 s and slowed the loop
  // 10^4-fold)
  std::vector<size_t> backlog_;
};

}  // namespace uavsim::server::radio
