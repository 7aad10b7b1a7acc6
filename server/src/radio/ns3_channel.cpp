#include "radio/ns3_channel.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "radio/radio_model.hpp"
#include "uavsim/common/splitmix.hpp"
#include "wire.hpp"

namespace uavsim::server::radio {

namespace {

namespace wire = uavsim::ns3wire;

constexpr double kTimeEps = 1e-9;
constexpr size_t kNs3MacHeaderBytes = 11;    // short addresses, compressed PAN id, FCS
constexpr double kLrWpanFloorDbm = -106.58;  // lr-wpan 3.37's fixed receiver sensitivity
constexpr double kObstacleLossChangeDb = 1e-9;
// TDMA on lr-wpan: a frame handed to the MAC at its slot's start still takes one clear-channel
// assessment (8 symbols, 128 us) and the receive-to-transmit turnaround (12 symbols, 192 us) before
// it goes on air (macMinBE 0: no random backoff), so a slot must hold those and the longest frame
constexpr double kNs3TdmaAccessS = 128e-6 + 192e-6;

wire::Channel wire_channel(const RadioConfig& c) {
  wire::Channel w;
  w.log_distance = c.propagation == Propagation::kLogDistance ? 1 : 0;
  w.range_m = c.range_m;
  w.tx_power_dbm = c.tx_power_dbm;
  w.sensitivity_dbm = c.sensitivity_dbm;
  w.reference_loss_db = c.reference_loss_db;
  w.path_loss_exponent = c.path_loss_exponent;
  w.shadowing_sigma_db = c.shadowing_sigma_db;
  w.tdma = c.tdma ? 1 : 0;
  w.technology = c.technology == Technology::k80211 ? 1 : 0;
  return w;
}

bool same_channel(const RadioConfig& a, const RadioConfig& b) {
  return a.propagation == b.propagation && a.range_m == b.range_m &&
         a.tx_power_dbm == b.tx_power_dbm && a.sensitivity_dbm == b.sensitivity_dbm &&
         a.reference_loss_db == b.reference_loss_db &&
         a.path_loss_exponent == b.path_loss_exponent &&
         a.shadowing_sigma_db == b.shadowing_sigma_db && a.tdma == b.tdma &&
         a.technology == b.technology;
}

}  // namespace

double Ns3Channel::min_tdma_slot_s() { return airtime_s(kMaxFrameBytes) + kNs3TdmaAccessS; }

std::string Ns3Channel::validate_ns3(const RadioConfig& c, size_t vehicles) {
  // the rules both backends share (finite numbers, ranges, TDMA's N D <= T), then what lr-wpan
  // fixes
  RadioConfig shared = c;
  shared.mac_header_bytes = 0;
  const std::string why = validate(shared, vehicles);
  if (!why.empty()) return why;
  if (c.tdma && c.technology != Technology::k802154) {
    return "tdma is the seed's 802.15.4 MAC: not with technology 802.11";
  }
  if (c.tdma && !(c.slot_s >= min_tdma_slot_s())) {
    return "slot_s must be at least " + std::to_string(min_tdma_slot_s()) +
           " s on the ns3 backend (a 127-byte frame's airtime, one clear-channel assessment and "
           "the turnaround to transmit)";
  }
  if (c.loss_probability != 0.0) {
    return "loss must be 0 on the ns3 backend (ns-3 loses frames by SINR, not by a draw)";
  }
  if (!c.collisions) return "collisions are always modelled on the ns3 backend";
  if (c.mac_header_bytes != kNs3MacHeaderBytes) {
    return "mac_header_bytes is " + std::to_string(kNs3MacHeaderBytes) +
           " on the ns3 backend (short addresses, compressed PAN id, FCS)";
  }
  if (c.sensitivity_dbm < kLrWpanFloorDbm) {
    return "sensitivity_dbm must be >= -106.58 on the ns3 backend (lr-wpan's own floor in ns-3 "
           "3.37)";
  }
  return "";
}

Ns3Channel::Ns3Channel(size_t vehicles, const RadioConfig& config, uint64_t seed, double step_s,
                       const Ns3Options& options)
    : vehicles_(vehicles), config_(config), step_s_(step_s), options_(options), seed_(seed) {
  // what ns-3 always does, whatever the simple model's defaults say
  config_.mac_header_bytes = kNs3MacHeaderBytes;
  config_.collisions = true;
  const std::string why = validate_ns3(config_, vehicles);
  if (!why.empty()) throw std::invalid_argument("radio config (ns3 backend): " + why);
  if (!(step_s > 0.0)) throw std::invalid_argument("radio: step_s must be > 0");
  if (vehicles == 0 || vehicles > wire::kMaxVehicles) {
    throw std::invalid_argument("radio (ns3 backend): needs 1 to " +
                                std::to_string(wire::kMaxVehicles) + " vehicles");
  }
  if (!(options.reply_timeout_s > 0.0 && options.reply_timeout_s <= 3600.0)) {
    throw std::invalid_argument("radio (ns3 backend): reply timeout must be in (0, 3600] s");
  }
  velocities_enu_m_s_.assign(vehicles, Eigen::Vector3d::Zero());
  spawn();
  wire::Writer w;
  w.put(static_cast<uint8_t>(wire::MessageType::kInit));
  w.put(static_cast<uint32_t>(vehicles));
  w.put(seed);
  wire::put_channel(w, wire_channel(config_));
  if (!expect_ready(w.message())) {
    // no destructor runs for a constructor that throws: fail() has reaped the helper, close its
    // socket
    ::close(fd_);
    fd_ = -1;
    throw std::runtime_error("radio (ns3 backend): " + failure_);
  }
  reset_state();
}

bool Ns3Channel::expect_ready(const std::vector<uint8_t>& request) {
  std::vector<uint8_t> reply;
  if (!exchange(request, &reply)) return false;
  wire::Reader in(reply.data(), reply.size());
  const auto type = in.get<uint8_t>();
  const auto max_payload = in.get<uint32_t>();
  if (!in.ok() || type != static_cast<uint8_t>(wire::MessageType::kReady) || max_payload == 0 ||
      max_payload > kLargestFrameBytes) {
    fail("a malformed ready answer");
    return false;
  }
  max_payload_bytes_ = max_payload;
  return true;
}

void Ns3Channel::reset_state() {
  requested_ns_ = 0;
  clock_ns_ = 0;
  busy_ = false;
  quiet_until_ns_ = 0;
  slices_.clear();
  slice_count_ = 0;
  queue_.clear();
  next_seq_.assign(vehicles_, 0);
  queued_.assign(vehicles_, 0);
  busy_until_s_.assign(vehicles_, 0.0);
  last_entry_ns_.assign(vehicles_, -1);
  in_flight_.assign(vehicles_, 0);
  pushed_loss_db_.assign(vehicles_ * vehicles_, 0.0);
  pending_.clear();
  links_.assign(vehicles_ * vehicles_, LinkStats{});
  transmitted_.assign(vehicles_, 0);
  access_failures_.assign(vehicles_, 0);
}

void Ns3Channel::reset(uint64_t seed) {
  collect();
  if (!failure_.empty()) return;
  wire::Writer w;
  w.put(static_cast<uint8_t>(wire::MessageType::kReset));
  w.put(seed);
  expect_ready(w.message());
  seed_ = seed;
  reset_state();
}

bool Ns3Channel::set_config(const RadioConfig& config, std::string* error) {
  const std::string why = validate_ns3(config, vehicles_);
  if (!why.empty()) {
    if (error != nullptr) *error = why;
    return false;
  }
  // what was stepped under the old settings goes first
  if (slice_count_ > 0 && failure_.empty()) send_step(-1, true);
  collect();
  if (!same_channel(config, config_) && failure_.empty()) {
    wire::Writer w;
    w.put(static_cast<uint8_t>(wire::MessageType::kConfig));
    wire::put_channel(w, wire_channel(config));
    if (!expect_ready(w.message())) {
      if (error != nullptr) *error = failure_;
      return false;
    }
    if (config.technology != config_.technology) {
      // the helper built a fresh world (its clock back at 0) with the other devices: whatever was
      // waiting or in flight is dropped (its size may not fit the new max_payload_bytes)
      for (const Queued& q : queue_) --queued_[q.from];
      queue_.clear();
      in_flight_.assign(vehicles_, 0);
      busy_until_s_.assign(vehicles_, 0.0);
      last_entry_ns_.assign(vehicles_, -1);
      busy_ = false;
      requested_ns_ = 0;
      clock_ns_ = 0;
      quiet_until_ns_ = 0;
    }
  }
  config_ = config;
  return true;
}

int64_t Ns3Channel::to_ns(double t_s) const { return std::llround(t_s * 1e9); }

int64_t Ns3Channel::entry_ns(size_t from, int64_t queued_ns) {
  const int64_t spread_ns = config_.technology == Technology::k80211
                                ? std::max(to_ns(config_.send_spread_s), to_ns(step_s_))
                                : to_ns(config_.send_spread_s);
  if (spread_ns <= 0) return -1;
  // splitmix64 of (seed, sender, send time): the frames a sender sends at one time share their
  // offset, as a program's frames of one tick leave together
  const uint64_t x =
      common::splitmix64_mix(seed_ ^ (static_cast<uint64_t>(from) * common::kSplitMixGamma) ^
                             (static_cast<uint64_t>(queued_ns) * 0xc2b2ae3d27d4eb4full));
  const int64_t at_ns = queued_ns + static_cast<int64_t>(x % static_cast<uint64_t>(spread_ns));
  // never before the sender's previous frame: a sender's frames go to its MAC in the order sent
  last_entry_ns_[from] = std::max(at_ns, last_entry_ns_[from]);
  return last_entry_ns_[from];
}

SendResult Ns3Channel::send(size_t from, int to, const std::vector<uint8_t>& data, double now_s) {
  SendResult r;
  if (from >= vehicles_ || (to != kBroadcast && (to < 0 || static_cast<size_t>(to) >= vehicles_))) {
    r.error = Error::kUnknownVehicle;
  } else if (to == static_cast<int>(from)) {
    r.error = Error::kBadDestination;
  } else if (data.empty()) {
    r.error = Error::kEmptyFrame;
  } else if (data.size() > max_payload_bytes_) {
    r.error = Error::kFrameTooLarge;
  } else if (!failure_.empty() || queued(from) >= config_.max_queue_frames) {
    // a failed helper takes nothing more (the run is ending)
    r.error = Error::kQueueFull;
  } else {
    Queued q;
    q.from = from;
    q.to = to;
    q.seq = next_seq_[from]++;
    q.queued_ns = to_ns(now_s);
    q.data = data;
    if (config_.tdma) {
      // the slot the simple model gives it: the sender's next own slot once its previous frame is
      // done (radio_model.hpp), so both backends put a frame on air in the same slot
      const double earliest_s = std::max(now_s, busy_until_s_[from]);
      const double start_s = tdma_slot_start_s(config_, vehicles_, from, earliest_s);
      busy_until_s_[from] = start_s + airtime_s(data.size() + kNs3MacHeaderBytes);
      q.slot_ns = to_ns(start_s);
    } else {
      q.slot_ns = entry_ns(from, q.queued_ns);
    }
    queue_.push_back(std::move(q));
    ++queued_[from];
    r.seq = queue_.back().seq;
  }
  return r;
}

bool Ns3Channel::has_due(double now_s) const {
  (void)now_s;
  // any queued frame, even one waiting for its TDMA slot: step() looks at every queued frame and
  // must have this step's positions for those it hands over (fetching them is cheap)
  return failure_.empty() && (!queue_.empty() || busy_);
}

void Ns3Channel::set_velocities(const std::vector<Eigen::Vector3d>& velocities_enu_m_s) {
  if (velocities_enu_m_s.size() == vehicles_) velocities_enu_m_s_ = velocities_enu_m_s;
}

std::vector<Ns3Channel::Queued> Ns3Channel::take_due(int64_t now_ns, bool starting_now) {
  // frames to hand over: those sent by now (with starting_now false, those sent before now: a
  // lockstep client may still send for now), in (time, sender, seq) order: the order ns-3's
  // MACs get them, whatever order the requests came in
  // TDMA: a frame is handed at the last step before its slot starts, and ns-3 puts it to its MAC
  // at the slot's start (within the step, from this step's positions and velocities)
  std::vector<Queued> hand;
  const int64_t step_ns = to_ns(step_s_);
  auto due = [&](const Queued& q) {
    const bool sent = starting_now ? q.queued_ns <= now_ns : q.queued_ns < now_ns;
    return sent && (q.slot_ns < 0 || q.slot_ns < now_ns + step_ns);
  };
  for (auto it = queue_.begin(); it != queue_.end();) {
    if (due(*it)) {
      hand.push_back(std::move(*it));
      it = queue_.erase(it);
    } else {
      ++it;
    }
  }
  std::stable_sort(hand.begin(), hand.end(), [](const Queued& a, const Queued& b) {
    if (a.queued_ns != b.queued_ns) return a.queued_ns < b.queued_ns;
    if (a.from != b.from) return a.from < b.from;
    return a.seq < b.seq;
  });
  return hand;
}

void Ns3Channel::add_slice(int64_t t_ns, const std::vector<Eigen::Vector3d>& positions_enu_m,
                           const std::vector<Queued>& hand) {
  wire::Writer w;
  w.put(t_ns);
  w.put<uint8_t>(1);
  for (size_t i = 0; i < vehicles_; ++i) {
    for (int k = 0; k < 3; ++k) w.put(positions_enu_m[i][k]);
    for (int k = 0; k < 3; ++k) w.put(velocities_enu_m_s_[i][k]);
  }
  // obstacle losses of the links this step's senders use (both ways: ACKs come back)
  std::vector<size_t> senders;
  for (const Queued& q : hand) senders.push_back(q.from);
  std::sort(senders.begin(), senders.end());
  senders.erase(std::unique(senders.begin(), senders.end()), senders.end());
  wire::Writer losses;
  uint32_t loss_count = 0;
  for (size_t s : senders) {
    for (size_t r = 0; r < vehicles_; ++r) {
      if (r == s) continue;
      const double db = link_loss_db(s, r);
      for (const auto& [a, b] : {std::pair{s, r}, std::pair{r, s}}) {
        double& pushed = pushed_loss_db_[a * vehicles_ + b];
        if (std::abs(pushed - db) <= kObstacleLossChangeDb) continue;
        pushed = db;
        losses.put(static_cast<uint32_t>(a));
        losses.put(static_cast<uint32_t>(b));
        losses.put(db);
        ++loss_count;
      }
    }
  }
  w.put(loss_count);
  w.append(losses);
  w.put(static_cast<uint32_t>(hand.size()));
  for (const Queued& q : hand) {
    w.put(static_cast<uint32_t>(q.from));
    w.put(static_cast<int32_t>(q.to));
    w.put(q.seq);
    w.put(q.queued_ns);
    w.put(q.slot_ns < 0 ? int64_t{-1} : std::max(q.slot_ns, t_ns));
    w.put(static_cast<uint16_t>(q.data.size()));
    w.bytes(q.data.data(), q.data.size());
    --queued_[q.from];
    ++in_flight_[q.from];
  }
  slices_.insert(slices_.end(), w.body().begin(), w.body().end());
  ++slice_count_;
}

void Ns3Channel::step(double now_s, const std::vector<Eigen::Vector3d>& positions_enu_m,
                      std::vector<Delivery>* out, bool starting_now) {
  const int64_t now_ns = to_ns(now_s);
  // the answer to the step sent ahead (the last call's): receptions up to now among them
  collect();
  std::vector<Queued> hand = take_due(now_ns, starting_now);
  // frames in flight report nothing before quiet_until_ns_ (the helper's bound): no slice before
  // it
  const bool advance = busy_ && now_ns > requested_ns_ && now_ns >= quiet_until_ns_;
  if (failure_.empty() && (!hand.empty() || advance) && now_ns >= requested_ns_ &&
      positions_enu_m.size() == vehicles_) {
    // a helper that ran past now (a call off the step grid, pipelined) takes the inputs at its own
    // time
    add_slice(std::max(now_ns, clock_ns_), positions_enu_m, hand);
    requested_ns_ = now_ns;
    // what the helper reports between its clock and now arrives now: wait for it, unless the
    // helper ran ahead to now, or its frames have nothing to report before now
    const bool reports_due = clock_ns_ < now_ns && busy_ && now_ns >= quiet_until_ns_;
    if (!pipelined_ || reports_due) send_step(-1, true);
  } else {
    for (const Queued& q : hand) --queued_[q.from];  // a failed helper: dropped
  }
  if (pipelined_ && starting_now && failure_.empty()) {
    // this time's last call: what it has goes now, and the helper runs on to the next step while
    // the server computes it. The next step's time as the caller's clock will say it: MuJoCo adds
    // the step to its time, and a sum rounded to nanoseconds can be 1 ns off now_ns + step
    const int64_t ahead_ns = to_ns(now_s + step_s_);
    if (slice_count_ > 0 || (busy_ && ahead_ns >= quiet_until_ns_)) send_step(ahead_ns, false);
  }

  // arrivals up to now, in (time, receiver, sender, seq) order
  take_arrivals(&pending_, now_s, out);
}

void Ns3Channel::send_step(int64_t ahead_ns, bool wait) {
  wire::Writer w;
  w.put(static_cast<uint8_t>(wire::MessageType::kStep));
  w.put(slice_count_);
  w.bytes(slices_.data(), slices_.size());
  w.put(ahead_ns);
  slices_.clear();
  slice_count_ = 0;
  if (!send_request(w.message())) return;
  outstanding_ = true;
  if (wait) collect();
}

void Ns3Channel::collect() {
  if (!outstanding_) return;
  outstanding_ = false;
  std::vector<uint8_t> reply;
  if (read_reply(&reply) && !read_step_done(reply)) fail("a malformed step answer");
}

void Ns3Channel::set_pipelined(bool on) {
  // the slices kept for the next send go first, in the mode they were made in
  if (pipelined_ && !on && slice_count_ > 0 && failure_.empty()) send_step(-1, true);
  collect();
  pipelined_ = on;
}

bool Ns3Channel::read_step_done(const std::vector<uint8_t>& reply) {
  wire::Reader in(reply.data(), reply.size());
  if (in.get<uint8_t>() != static_cast<uint8_t>(wire::MessageType::kStepDone)) return false;
  const auto clock_ns = in.get<int64_t>();
  if (!in.ok() || clock_ns < clock_ns_) return false;
  clock_ns_ = clock_ns;
  const bool busy = in.get<uint8_t>() != 0;
  const auto quiet_until_ns = in.get<int64_t>();
  // receptions: they arrive after the processing latency, and never before one step after they
  // were sent (as on the simple backend)
  const auto deliveries = in.get<uint32_t>();
  if (!in.ok() || deliveries > in.left() / 45) return false;
  for (uint32_t k = 0; k < deliveries; ++k) {
    Delivery d;
    const auto to = in.get<uint32_t>();
    const auto from = in.get<uint32_t>();
    d.seq = in.get<uint64_t>();
    d.broadcast = in.get<uint8_t>() != 0;
    const auto queued_ns = in.get<int64_t>();
    const auto tx_start_ns = in.get<int64_t>();
    const auto rx_ns = in.get<int64_t>();
    in.get<uint8_t>();  // LQI
    const auto n = in.get<uint16_t>();
    if (!in.ok() || to >= vehicles_ || from >= vehicles_ || n == 0 || n > max_payload_bytes_ ||
        !in.bytes(n, &d.data)) {
      return false;
    }
    d.to = to;
    d.from = from;
    d.queued_s = static_cast<double>(queued_ns) * 1e-9;
    d.tx_start_s = static_cast<double>(tx_start_ns) * 1e-9;
    d.time_s =
        std::max(static_cast<double>(rx_ns) * 1e-9 + config_.latency_s, d.queued_s + step_s_);
    pending_.push_back(std::move(d));
  }
  const auto confirms = in.get<uint32_t>();
  if (!in.ok() || confirms > in.left() / 13) return false;
  for (uint32_t k = 0; k < confirms; ++k) {
    const auto from = in.get<uint32_t>();
    in.get<uint64_t>();
    in.get<uint8_t>();
    if (!in.ok() || from >= vehicles_ || in_flight_[from] == 0) return false;
    --in_flight_[from];
  }
  const auto counters = in.get<uint32_t>();
  if (!in.ok() || counters > in.left() / 9) return false;
  for (uint32_t k = 0; k < counters; ++k) {
    const auto from = in.get<uint32_t>();
    const auto to = in.get<uint32_t>();
    const auto kind = static_cast<wire::Counter>(in.get<uint8_t>());
    if (!in.ok() || from >= vehicles_ || to >= vehicles_) return false;
    LinkStats& s = links_[from * vehicles_ + to];
    switch (kind) {
      case wire::Counter::kSent:
        ++s.sent;
        break;
      case wire::Counter::kDelivered:
        ++s.delivered;
        break;
      case wire::Counter::kLost:
        ++s.lost;
        break;
      case wire::Counter::kOutOfRange:
        ++s.out_of_range;
        break;
      case wire::Counter::kNoAck:
        ++s.no_ack;
        break;
      case wire::Counter::kTransmitted:
        ++transmitted_[from];
        break;
      case wire::Counter::kChannelAccessFailure:
        ++access_failures_[from];
        break;
      default:
        return false;
    }
  }
  busy_ = busy;
  quiet_until_ns_ = quiet_until_ns;
  return in.ok() && in.left() == 0;
}

}  // namespace uavsim::server::radio
