#include "api/lockstep_coordinator.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <utility>

namespace uavsim::server::api {

namespace {
// a period or busy_until that is a whole number of periods up to rounding falls on that multiple
constexpr double kMultipleTol = 1e-9;

double next_multiple(double t_s, double period_s) {
  return std::ceil(t_s / period_s - kMultipleTol) * period_s;
}
}  // namespace

LockstepCoordinator::LockstepCoordinator(double control_dt_s, double physics_dt_s,
                                         double default_timeout_s, WallClock now_s)
    : control_dt_s_(control_dt_s),
      eps_s_(0.25 * physics_dt_s),
      default_timeout_s_(default_timeout_s),
      now_s_(std::move(now_s)) {}

LockstepCoordinator::Joined LockstepCoordinator::join(uint64_t conn, double period_s,
                                                      std::optional<double> timeout_s,
                                                      double sim_time_s) {
  // whole control steps, at least one; the first tick is the next multiple of the period
  dropped_.erase(conn);
  Client& c = clients_[conn];
  const int64_t period_steps = std::max<int64_t>(1, std::llround(period_s / control_dt_s_));
  c.period_s = static_cast<double>(period_steps) * control_dt_s_;
  c.awaiting = false;
  c.timeout_s = timeout_s.value_or(default_timeout_s_);
  c.next_due_s = next_multiple(sim_time_s, c.period_s);
  return {c.period_s, c.next_due_s, c.timeout_s};
}

std::optional<double> LockstepCoordinator::leave(uint64_t conn, double sim_time_s) {
  dropped_.erase(conn);  // it left (or disconnected): nothing more to tell it
  auto it = clients_.find(conn);
  if (it == clients_.end()) return std::nullopt;
  const Client c = it->second;
  clients_.erase(it);
  // the clock cannot pass the client's next tick without it, so that is where it left (a done
  // already sent counts as the tick completed)
  const double left_at_s = c.awaiting ? (c.done_received ? c.tick_time_s + c.period_s : c.tick_time_s)
                                      : std::max(sim_time_s, c.next_due_s);
  // the latest of the leaving clients' ticks, not the one whose leaving was noticed last: two
  // programs that end near the same tick are noticed in either order (wall-clock timing), and
  // the run's end must not depend on it
  latest_left_at_s_ = std::max(latest_left_at_s_.value_or(left_at_s), left_at_s);
  if (!clients_.empty()) return std::nullopt;
  const double last = *latest_left_at_s_;
  latest_left_at_s_.reset();
  return last;
}

bool LockstepCoordinator::joined(uint64_t conn) const { return clients_.count(conn) > 0; }

std::vector<uint64_t> LockstepCoordinator::due(double sim_time_s) const {
  std::vector<uint64_t> out;
  for (const auto& [conn, c] : clients_) {
    if (!c.awaiting && sim_time_s + eps_s_ >= c.next_due_s) out.push_back(conn);
  }
  return out;
}

int64_t LockstepCoordinator::begin_tick(uint64_t conn, double sim_time_s) {
  Client& c = clients_.at(conn);
  c.awaiting = true;
  c.done_received = false;
  c.wait_seq.clear();
  c.busy_until_s.reset();
  c.tick = std::llround(sim_time_s / c.period_s);
  c.tick_time_s = sim_time_s;
  c.deadline_s = now_s_() + c.timeout_s;
  return c.tick;
}

std::optional<common::ApiError> LockstepCoordinator::check_done(uint64_t conn, std::optional<double> tick,
                                            std::string* message) const {
  auto it = clients_.find(conn);
  if (it == clients_.end()) {
    if (const auto d = dropped_.find(conn); d != dropped_.end()) {
      char buf[256];
      std::snprintf(buf, sizeof(buf),
                    "this connection was dropped from the lockstep at sim time %.3f s: no \"done\" for "
                    "tick %lld within its timeout of %g s of wall time, and the clock went on without "
                    "it; lockstep_join to take part again",
                    d->second.sim_time_s, static_cast<long long>(d->second.tick), d->second.timeout_s);
      *message = buf;
      return common::ApiError::kNotJoined;
    }
    *message = "\"done\" without lockstep_join";
    return common::ApiError::kNotJoined;
  }
  const Client& c = it->second;
  if (!c.awaiting || c.done_received) {
    *message = "no tick is waiting for \"done\"";
    return common::ApiError::kBadState;
  }
  if (tick && *tick != static_cast<double>(c.tick)) {
    *message = "the tick waiting is " + std::to_string(c.tick);
    return common::ApiError::kBadField;
  }
  return std::nullopt;
}

int64_t LockstepCoordinator::take_done(uint64_t conn, std::optional<double> busy_until_s,
                                       std::map<size_t, uint8_t> wait_seq) {
  Client& c = clients_.at(conn);
  c.done_received = true;
  c.wait_seq = std::move(wait_seq);
  c.busy_until_s = busy_until_s;
  return c.tick;
}

void LockstepCoordinator::complete(const SeqProcessed& seq_processed) {
  for (auto& [conn, c] : clients_) {
    if (!c.awaiting || !c.done_received) continue;
    // the MAVLink messages the client sent before "done" must have been handled
    bool seq_ok = true;
    if (seq_processed) {
      for (const auto& [vehicle, seq] : c.wait_seq) seq_ok = seq_ok && seq_processed(vehicle, seq);
    }
    if (!seq_ok) continue;
    c.awaiting = false;
    c.next_due_s = c.tick_time_s + c.period_s;
    if (c.busy_until_s && *c.busy_until_s > c.next_due_s) {
      // detached timing: the next tick for this client is the first one at or after busy_until
      c.next_due_s = next_multiple(*c.busy_until_s, c.period_s);
    }
  }
}

bool LockstepCoordinator::blocked() const {
  return std::any_of(clients_.begin(), clients_.end(),
                     [](const auto& kv) { return kv.second.awaiting; });
}

std::vector<LockstepCoordinator::Dropped> LockstepCoordinator::expire(double sim_time_s) {
  const double now = now_s_();
  std::vector<uint64_t> late;
  for (const auto& [conn, c] : clients_) {
    if (c.awaiting && now >= c.deadline_s) late.push_back(conn);
  }
  std::vector<Dropped> dropped;
  for (uint64_t conn : late) {
    const Client& c = clients_.at(conn);
    const DropRecord record{sim_time_s, c.tick, c.timeout_s};
    dropped.push_back({conn, leave(conn, sim_time_s)});
    dropped_[conn] = record;  // after leave(), which forgets a connection's drop
    if (dropped_.size() > kMaxDropRecords) dropped_.erase(dropped_.begin());
  }
  return dropped;
}

std::optional<double> LockstepCoordinator::deadline_s() const {
  std::optional<double> earliest;
  for (const auto& [conn, c] : clients_) {
    if (c.awaiting && (!earliest || c.deadline_s < *earliest)) earliest = c.deadline_s;
  }
  return earliest;
}

bool LockstepCoordinator::waiting_on_seq() const {
  return std::any_of(clients_.begin(), clients_.end(),
                     [](const auto& kv) { return kv.second.awaiting && kv.second.done_received; });
}

void LockstepCoordinator::reset() {
  latest_left_at_s_.reset();
  for (auto& [conn, c] : clients_) {
    c.awaiting = false;
    c.next_due_s = 0.0;
  }
}

}  // namespace uavsim::server::api
