#include "radio/radio_model.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "uavsim/common/angles.hpp"

namespace uavsim::server::radio {

namespace {

// times are sums of step multiples and slot arithmetic: compare with a tolerance far below any step
constexpr double kTimeEps = 1e-9;

bool frame_before(double start_a, size_t from_a, uint64_t seq_a, double start_b, size_t from_b,
                  uint64_t seq_b) {
  if (start_a != start_b) return start_a < start_b;
  if (from_a != from_b) return from_a < from_b;
  return seq_a < seq_b;
}

// a bound as a person writes it: 1e+06, 0.004256, -150
std::string number_text(double v) {
  std::ostringstream out;
  out << v;
  return out.str();
}

}  // namespace

double airtime_s(size_t frame_bytes) {
  return static_cast<double>((frame_bytes + kPhyOverheadBytes) * 8) / kBitRateBitS;
}

void take_arrivals(std::vector<Delivery>* pending, double now_s, std::vector<Delivery>* out) {
  auto arrived = std::stable_partition(pending->begin(), pending->end(), [&](const Delivery& d) {
    return d.time_s > now_s + kTimeEps;
  });
  std::vector<Delivery> ready(std::make_move_iterator(arrived),
                              std::make_move_iterator(pending->end()));
  pending->erase(arrived, pending->end());
  std::sort(ready.begin(), ready.end(), [](const Delivery& a, const Delivery& b) {
    if (a.time_s != b.time_s) return a.time_s < b.time_s;
    if (a.to != b.to) return a.to < b.to;
    if (a.from != b.from) return a.from < b.from;
    return a.seq < b.seq;
  });
  for (Delivery& d : ready) out->push_back(std::move(d));
}

const char* propagation_name(Propagation p) {
  return p == Propagation::kRange ? "range" : "log_distance";
}

std::optional<Propagation> propagation_from_name(const std::string& name) {
  if (name == "range") return Propagation::kRange;
  if (name == "log_distance") return Propagation::kLogDistance;
  return std::nullopt;
}

const char* technology_name(Technology t) {
  return t == Technology::k802154 ? "802.15.4" : "802.11";
}

std::optional<Technology> technology_from_name(const std::string& name) {
  if (name == "802.15.4") return Technology::k802154;
  if (name == "802.11") return Technology::k80211;
  return std::nullopt;
}

const char* error_name(Error e) {
  switch (e) {
    case Error::kUnknownVehicle:
      return "unknown_vehicle";
    case Error::kBadDestination:
      return "bad_destination";
    case Error::kEmptyFrame:
      return "empty_frame";
    case Error::kFrameTooLarge:
      return "frame_too_large";
    case Error::kQueueFull:
      return "queue_full";
  }
  return "unknown";
}

std::string validate(const RadioConfig& c, size_t vehicles) {
  // every number of a config comes from outside (API, world): each is finite and within the
  // physical range its field states (radio_model.hpp), so no value reaches a loop, a log or a cast
  // unusable
  const auto in = [](double v, double lo, double hi) {
    return std::isfinite(v) && v >= lo && v <= hi;
  };
  const auto range = [](const char* name, double lo, double hi) {
    return std::string(name) + " must be in [" + number_text(lo) + ", " + number_text(hi) + "]";
  };
  if (!in(c.range_m, kMinRangeM, kMaxRangeM)) return range("range_m", kMinRangeM, kMaxRangeM);
  if (!in(c.tx_power_dbm, kMinTxPowerDbm, kMaxTxPowerDbm))
    return range("tx_power_dbm", kMinTxPowerDbm, kMaxTxPowerDbm);
  if (!in(c.sensitivity_dbm, kMinSensitivityDbm, kMaxSensitivityDbm))
    return range("sensitivity_dbm", kMinSensitivityDbm, kMaxSensitivityDbm);
  if (!in(c.reference_loss_db, 0.0, kMaxLossDb)) return range("reference_loss_db", 0.0, kMaxLossDb);
  if (!in(c.path_loss_exponent, kMinPathLossExponent, kMaxPathLossExponent))
    return range("path_loss_exponent", kMinPathLossExponent, kMaxPathLossExponent);
  if (!in(c.shadowing_sigma_db, 0.0, kMaxShadowingSigmaDb))
    return range("shadowing_sigma_db", 0.0, kMaxShadowingSigmaDb);
  if (!in(c.loss_probability, 0.0, 1.0)) return "loss_probability must be in [0, 1]";
  if (!in(c.latency_s, 0.0, kMaxLatencyS)) return range("latency_s", 0.0, kMaxLatencyS);
  if (!in(c.send_spread_s, 0.0, kMaxSendSpreadS))
    return range("send_spread_s", 0.0, kMaxSendSpreadS);
  if (c.send_spread_s > 0.0 && c.tdma) return "send_spread_s must be 0 with tdma (slots are exact)";
  if (c.max_queue_frames == 0) return "max_queue_frames must be > 0";
  if (c.mac_header_bytes > kMaxMacHeaderBytes)
    return "mac_header_bytes must be in [0, " + std::to_string(kMaxMacHeaderBytes) + "]";
  for (double loss_db : c.obstacle_loss_db) {
    if (!(loss_db >= 0.0 && loss_db <= 1000.0)) return "obstacle_loss_db must be in [0, 1000] dB";
  }
  if (c.tdma) {
    // seed 6.2: D < T/N, and a slot must hold the longest frame; T at most an hour keeps the slot
    // count T / D below a million
    if (!in(c.period_s, airtime_s(kMaxFrameBytes), kMaxPeriodS))
      return range("period_s", airtime_s(kMaxFrameBytes), kMaxPeriodS);
    if (!(std::isfinite(c.slot_s) && c.slot_s >= airtime_s(kMaxFrameBytes))) {
      return "slot_s must be at least the airtime of a 127-byte frame (" +
             std::to_string(airtime_s(kMaxFrameBytes)) + " s)";
    }
    if (c.slot_s * static_cast<double>(vehicles) > c.period_s * (1.0 + 1e-12)) {
      return "slot_s * vehicles (" + std::to_string(vehicles) + ") must not exceed period_s";
    }
  }
  return "";
}

std::string RadioModel::validate_simple(const RadioConfig& config, size_t vehicles) {
  if (config.technology != Technology::k802154) {
    return "technology 802.11 needs the ns3 backend (the simple model is 802.15.4's)";
  }
  if (config.send_spread_s != 0.0) {
    return "send_spread_s needs the ns3 backend (the simple model has no medium access to spread "
           "for)";
  }
  return validate(config, vehicles);
}

RadioModel::RadioModel(size_t vehicles, const RadioConfig& config, uint64_t seed, double step_s)
    : vehicles_(vehicles), config_(config), step_s_(step_s), rng_(seed) {
  const std::string why = validate_simple(config, vehicles);
  if (!why.empty()) throw std::invalid_argument("radio config: " + why);
  if (!(step_s > 0.0)) throw std::invalid_argument("radio: step_s must be > 0");
  reset(seed);
}

void RadioModel::reset(uint64_t seed) {
  rng_.seed(seed);
  queues_.assign(vehicles_, {});
  next_seq_.assign(vehicles_, 0);
  busy_until_s_.assign(vehicles_, 0.0);
  scheduled_.clear();
  air_.clear();
  pending_.clear();
  links_.assign(vehicles_ * vehicles_, LinkStats{});
  transmitted_.assign(vehicles_, 0);
  backlog_.assign(vehicles_, 0);
}

bool RadioModel::set_config(const RadioConfig& config, std::string* error) {
  const std::string why = validate_simple(config, vehicles_);
  if (!why.empty()) {
    if (error != nullptr) *error = why;
    return false;
  }
  config_ = config;
  return true;
}

SendResult RadioModel::send(size_t from, int to, const std::vector<uint8_t>& data, double now_s) {
  SendResult r;
  if (from >= vehicles_) {
    r.error = Error::kUnknownVehicle;
  } else if (to != kBroadcast && (to < 0 || static_cast<size_t>(to) >= vehicles_)) {
    r.error = Error::kUnknownVehicle;
  } else if (to == static_cast<int>(from)) {
    r.error = Error::kBadDestination;
  } else if (data.empty()) {
    r.error = Error::kEmptyFrame;
  } else if (data.size() > max_payload_bytes()) {
    r.error = Error::kFrameTooLarge;
  } else if (backlog_[from] >= config_.max_queue_frames) {
    r.error = Error::kQueueFull;
  } else {
    Frame f;
    f.from = from;
    f.to = to;
    f.seq = next_seq_[from]++;
    f.queued_s = now_s;
    f.data = data;
    queues_[from].push_back(std::move(f));
    ++backlog_[from];
    r.seq = queues_[from].back().seq;
  }
  return r;
}

bool RadioModel::has_due(double now_s) const {
  for (const auto& q : queues_) {
    if (!q.empty()) return true;
  }
  return !scheduled_.empty() && scheduled_.front().start_s <= now_s + kTimeEps;
}

double tdma_slot_start_s(const RadioConfig& config, size_t vehicles, size_t vehicle, double t_s) {
  const double T = config.period_s;
  const double D = config.slot_s;
  // whole slots in a period; the remainder is wasted (seed 6.2). validate() bounds T / D below a
  // million and guarantees a slot to every vehicle (N D <= T), so the count is a safe integer and
  // the answer lies in this period or the next: no loop over slots or periods
  const auto slots = static_cast<uint64_t>(std::floor(T / D + 1e-9));
  const auto n = static_cast<uint64_t>(vehicles);
  const double period_start = std::floor(t_s / T) * T;
  // the first slot of this period that starts at or after t_s (within kTimeEps)
  const double into_s = std::max(0.0, t_s - kTimeEps - period_start);
  const auto first =
      static_cast<uint64_t>(std::min(std::ceil(into_s / D - 1e-9), static_cast<double>(slots)));
  // this vehicle's slots are vehicle, vehicle + N, ...: the first of them at or after `first`
  uint64_t k = vehicle;
  if (first > k) k += (first - k + n - 1) / n * n;
  if (k < slots) {
    const double s = period_start + static_cast<double>(k) * D;
    if (s >= t_s - kTimeEps) return s;
    k += n;  // rounding put the candidate just before t_s: the vehicle's next slot
    if (k < slots) return period_start + static_cast<double>(k) * D;
  }
  return period_start + T + static_cast<double>(vehicle) * D;
}

double RadioModel::next_slot_start_s(size_t vehicle, double t_s) const {
  return tdma_slot_start_s(config_, vehicles_, vehicle, t_s);
}

double RadioModel::uniform() {
  // 53 random bits -> [0, 1): the same on every standard library
  return static_cast<double>(rng_() >> 11) * (1.0 / 9007199254740992.0);
}

double RadioModel::normal() {
  // Box-Muller (one of the pair), portable unlike std::normal_distribution
  const double u1 = 1.0 - uniform();  // (0, 1]
  const double u2 = uniform();
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * common::kPi * u2);
}

bool RadioModel::reaches(size_t from, size_t to, const Eigen::Vector3d& a,
                         const Eigen::Vector3d& b) {
  const double d_m = (a - b).norm();
  // obstacles on the path (radio/line_of_sight.hpp): with the range model a loss of L dB shrinks
  // the range as the log-distance law would, by 10^(-L / (10 n))
  const double blocked_db = link_loss_db(from, to);
  if (config_.propagation == Propagation::kRange) {
    return d_m <=
           config_.range_m * std::pow(10.0, -blocked_db / (10.0 * config_.path_loss_exponent));
  }
  // log-distance path loss from a 1 m reference, plus a zero-mean gaussian shadowing term in dB
  const double path_loss_db = config_.reference_loss_db +
                              10.0 * config_.path_loss_exponent * std::log10(std::max(d_m, 1.0)) +
                              config_.shadowing_sigma_db * normal() + blocked_db;
  return config_.tx_power_dbm - path_loss_db >= config_.sensitivity_dbm;
}

void RadioModel::go_on_air(Frame& f, const std::vector<Eigen::Vector3d>& positions) {
  // (sender position, receiver positions) at the transmit instant => heard, dropped per receiver
  f.heard.assign(vehicles_, 0);
  f.dropped.assign(vehicles_, 0);
  ++transmitted_[f.from];
  --backlog_[f.from];
  for (size_t r = 0; r < vehicles_; ++r) {
    if (r == f.from) continue;
    f.heard[r] = reaches(f.from, r, positions[f.from], positions[r]) ? 1 : 0;
  }
  for (size_t r = 0; r < vehicles_; ++r) {
    if (r == f.from || (f.to != kBroadcast && static_cast<size_t>(f.to) != r)) continue;
    ++links_[f.from * vehicles_ + r].sent;
    if (f.heard[r] && config_.loss_probability > 0.0)
      f.dropped[r] = uniform() < config_.loss_probability;
  }
}

void RadioModel::resolve(const Frame& f, std::vector<Delivery>* arrivals) {
  for (size_t r = 0; r < vehicles_; ++r) {
    if (r == f.from || (f.to != kBroadcast && static_cast<size_t>(f.to) != r)) continue;
    LinkStats& link = links_[f.from * vehicles_ + r];
    if (!f.heard[r]) {
      ++link.out_of_range;
      continue;
    }
    bool collided = false;
    if (config_.collisions) {
      // another transmission overlapping this one that r hears, or r's own (half duplex)
      for (const Frame& g : air_) {
        if (g.from == f.from && g.seq == f.seq) continue;
        const bool overlap = g.start_s < f.end_s - kTimeEps && f.start_s < g.end_s - kTimeEps;
        if (overlap && (g.from == r || g.heard[r])) {
          collided = true;
          break;
        }
      }
    }
    if (collided) {
      ++link.collided;
    } else if (f.dropped[r]) {
      ++link.lost;
    } else {
      ++link.delivered;
      Delivery d;
      d.to = r;
      d.from = f.from;
      d.seq = f.seq;
      d.broadcast = f.to == kBroadcast;
      d.queued_s = f.queued_s;
      d.tx_start_s = f.start_s;
      d.time_s = std::max(f.end_s + config_.latency_s, f.queued_s + step_s_);
      d.data = f.data;
      arrivals->push_back(std::move(d));
    }
  }
}

void RadioModel::step(double now_s, const std::vector<Eigen::Vector3d>& positions_enu_m,
                      std::vector<Delivery>* out, bool starting_now) {
  // schedule queued frames: after the sender's previous frame, and in TDMA at its next own slot
  const size_t scheduled_before = scheduled_.size();
  for (size_t v = 0; v < vehicles_; ++v) {
    while (!queues_[v].empty()) {
      Frame f = std::move(queues_[v].front());
      queues_[v].pop_front();
      const double earliest = std::max(f.queued_s, busy_until_s_[v]);
      f.start_s = config_.tdma ? next_slot_start_s(v, earliest) : earliest;
      f.end_s = f.start_s + airtime_s(f.data.size() + config_.mac_header_bytes);
      busy_until_s_[v] = f.end_s;
      scheduled_.push_back(std::move(f));
    }
  }
  if (scheduled_.size() > scheduled_before) {
    // the new frames sorted among themselves, then merged into the sorted rest: linear in the
    // backlog, not a sort of it every step
    const auto before = [](const Frame& a, const Frame& b) {
      return frame_before(a.start_s, a.from, a.seq, b.start_s, b.from, b.seq);
    };
    const auto added = scheduled_.begin() + static_cast<std::ptrdiff_t>(scheduled_before);
    std::stable_sort(added, scheduled_.end(), before);
    std::inplace_merge(scheduled_.begin(), added, scheduled_.end(), before);
  }

  // due frames go on air, in (start, sender, seq) order: the order of the random draws
  const double on_air_until_s = starting_now ? now_s + kTimeEps : now_s - kTimeEps;
  size_t due = 0;
  while (due < scheduled_.size() && scheduled_[due].start_s <= on_air_until_s) {
    go_on_air(scheduled_[due], positions_enu_m);
    air_.push_back(std::move(scheduled_[due]));
    ++due;
  }
  scheduled_.erase(scheduled_.begin(), scheduled_.begin() + static_cast<std::ptrdiff_t>(due));

  // frames whose transmission has ended: every overlapping one is on air by now
  for (Frame& f : air_) {
    if (f.resolved || f.end_s > now_s + kTimeEps) continue;
    resolve(f, &pending_);
    f.resolved = true;
  }
  // forget transmissions too old to overlap anything still unresolved
  const double horizon_s = now_s - airtime_s(kMaxFrameBytes) - 2.0 * step_s_;
  air_.erase(std::remove_if(air_.begin(), air_.end(),
                            [&](const Frame& f) { return f.resolved && f.end_s < horizon_s; }),
             air_.end());

  // arrivals up to now, in (time, receiver, sender, seq) order
  take_arrivals(&pending_, now_s, out);
}

}  // namespace uavsim::server::radio
