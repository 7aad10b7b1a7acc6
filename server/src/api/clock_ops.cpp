#include "api/clock_ops.hpp"

#include <cmath>
#include <functional>
#include <string>

#include "api/request_fields.hpp"
#include "sim/checked_number.hpp"

namespace uavsim::server::api {

namespace {

// set_rate's range: above kMaxRate "as fast as possible" (0) is meant; below kMinRate a control
// step would take minutes of wall time
constexpr double kMaxRate = 1e6;
constexpr double kMinRate = 1e-3;

}  // namespace

ClockOps::ClockOps(sim::Simulation& sim, sim::Runner* runner, const LockstepCoordinator& lockstep,
                   bool start_paused, Send send, ResetGroups reset_groups)
    : sim_(sim),
      runner_(runner),
      lockstep_(lockstep),
      send_(std::move(send)),
      reset_groups_(std::move(reset_groups)),
      paused_(start_paused) {}

void ClockOps::register_ops(OpTable& table) {
  const OpRegistrar<ClockOps> add(table, this, "clock");
  add("status", &ClockOps::op_status);
  add("pause", &ClockOps::op_pause);
  add("pause_at", &ClockOps::op_pause_at);
  add("resume", &ClockOps::op_resume);
  add("step", &ClockOps::op_step);
  add("set_rate", &ClockOps::op_set_rate);
  add("reset", &ClockOps::op_reset);
}

void ClockOps::on_reset() {
  pause_at_s_.clear();
  pause_when_lockstep_empty_ = false;
}

void ClockOps::on_disconnect(uint64_t conn) {
  if (!step_in_progress(conn)) return;
  step_reply_.reset();
  replies_behind_step_.clear();
}

void ClockOps::arm_due_pauses() {
  // a quarter physics step of slack: sim time is a sum of steps
  const double held_by_s = sim_.time_s() + 0.25 * sim_.physics_dt_s();
  if (pause_at_s_.empty() || held_by_s < *pause_at_s_.begin()) return;
  paused_ = true;
  pause_at_s_.erase(pause_at_s_.begin(), pause_at_s_.upper_bound(held_by_s));
}

bool ClockOps::count_down_step() {
  if (steps_remaining_ > 0) {
    --steps_remaining_;
    return true;
  }
  if (step_reply_) finish_step();
  return false;
}

bool ClockOps::hold_reply(uint64_t conn, const Json& message) {
  if (!step_in_progress(conn)) return false;
  replies_behind_step_.push_back(message);
  return true;
}

void ClockOps::lockstep_left(std::optional<double> last_at_s) {
  // pause_at lockstep_empty: the last client's tick is the same sim time in every run, whenever its
  // leaving is noticed
  if (!last_at_s || !pause_when_lockstep_empty_) return;
  pause_at_s_.insert(*last_at_s);
  pause_when_lockstep_empty_ = false;
}

void ClockOps::finish_step(const char* by_op) {
  if (!step_reply_) return;
  const auto [conn, id] = *step_reply_;
  step_reply_.reset();
  if (by_op == nullptr) {
    send_(conn, ok_reply(id, {{"time_s", sim_.time_s()}, {"paused", true}}));
  } else {
    // another clock op took the clock: the step ends here, and says how far it got (the time as the
    // wire writes it)
    const uint64_t done = steps_requested_ - steps_remaining_;
    const std::string time =
        Json(sim_.time_s()).dump(-1, ' ', false, Json::error_handler_t::replace);
    send_(conn,
          error_reply(id, ApiError::kInterrupted,
                      std::string("a ") + by_op + " ended the step after " + std::to_string(done) +
                          " of " + std::to_string(steps_requested_) + " steps, at time_s " + time));
    steps_remaining_ = 0;
  }
  for (const Json& held : replies_behind_step_) send_(conn, held);
  replies_behind_step_.clear();
}

// ---------------------------------------------------------------------------------------------------
// the ops

void ClockOps::op_status(uint64_t, const Json&, OpReply* reply) {
  reply->result = {{"protocol", kProtocolVersion},
                   {"time_s", sim_.time_s()},
                   {"steps", sim_.step_count()},
                   {"paused", paused_},
                   {"rate", runner_ ? Json(runner_->rate()) : Json(nullptr)},
                   {"physics_hz", 1.0 / sim_.physics_dt_s()},
                   {"control_hz", 1.0 / sim_.control_dt_s()},
                   {"seed", sim_.config().seed},
                   {"vehicles", sim_.vehicle_count()},
                   {"lockstep_clients", lockstep_.client_count()},
                   {"events", sim_.events().next_seq()},
                   {"realism", sim::realism_name(sim_.config().field.realism)}};
}

void ClockOps::op_pause(uint64_t, const Json&, OpReply* reply) {
  finish_step("pause");
  paused_ = true;
  reply->result = {{"time_s", sim_.time_s()}, {"paused", true}};
}

void ClockOps::op_pause_at(uint64_t, const Json& request, OpReply* reply) {
  // arm a pause at a sim time and/or when the last lockstep client leaves (deterministic ends)
  const auto at = number_field(request, "time_s");
  const bool empty = request.value("lockstep_empty", false);
  if (!at && !empty) {
    return reply->fail(ApiError::kMissingField,
                       "\"time_s\" or \"lockstep_empty\": true is required");
  }
  if (at && !std::isfinite(*at)) {
    return reply->fail(ApiError::kBadField, "\"time_s\" must be a finite sim time");
  }
  if (at) pause_at_s_.insert(*at);
  if (empty) pause_when_lockstep_empty_ = true;
  reply->result = {
      {"time_s", sim_.time_s()},
      {"pause_at_s", Json(std::vector<double>(pause_at_s_.begin(), pause_at_s_.end()))},
      {"lockstep_empty", pause_when_lockstep_empty_}};
}

void ClockOps::op_resume(uint64_t, const Json&, OpReply* reply) {
  finish_step("resume");
  paused_ = false;
  steps_remaining_ = 0;
  reply->result = {{"time_s", sim_.time_s()}, {"paused", false}};
}

void ClockOps::op_step(uint64_t conn, const Json& request, OpReply* reply) {
  // N control steps (default 1) or a duration rounded to whole control steps; pauses first
  const auto steps = number_field(request, "steps");
  const auto duration = number_field(request, "duration_s");
  double n = 1;
  if (steps) n = *steps;
  if (duration) n = std::round(*duration / sim_.control_dt_s());
  if (!(n >= 1 && n <= 1e9) || std::floor(n) != n) {
    return reply->fail(
        ApiError::kBadField,
        "\"steps\" must be an integer in [1, 1e9] (or \"duration_s\" at least one control step)");
  }
  if (step_reply_) return reply->fail(ApiError::kBusy, "another step request is in progress");
  paused_ = true;
  steps_remaining_ = static_cast<uint64_t>(n);
  steps_requested_ = steps_remaining_;
  step_reply_ = std::make_pair(conn, request.contains("id") ? request["id"] : Json(nullptr));
  reply->deferred = true;  // answered when the steps are done
}

void ClockOps::op_set_rate(uint64_t, const Json& request, OpReply* reply) {
  const auto rate = number_field(request, "rate");
  if (!rate) {
    return reply->fail(ApiError::kMissingField,
                       "\"rate\" (a number: 1 = real time, 0 = as fast as possible) is required");
  }
  if (*rate != 0.0 && !sim::finite_in(*rate, kMinRate, kMaxRate)) {
    return reply->fail(ApiError::kBadField,
                       "\"rate\" must be 0 (as fast as possible) or in [0.001, 1e6]");
  }
  if (runner_ == nullptr) {
    return reply->fail(ApiError::kNotAvailable, "this server has no clock runner");
  }
  runner_->set_rate(*rate);
  reply->result = {{"rate", *rate}};
}

void ClockOps::op_reset(uint64_t, const Json& request, OpReply* reply) {
  // an integer seed travels exactly; a number in double form must be a whole one below 2^64
  const auto it = request.find("seed");
  std::optional<uint64_t> seed;
  if (it != request.end()) {
    seed = it->is_number_unsigned() ? std::optional<uint64_t>(it->get<uint64_t>())
                                    : sim::checked_integer<uint64_t>(it->get<double>());
  }
  if (it != request.end() && !seed) {
    return reply->fail(ApiError::kBadField, "\"seed\" must be an integer in [0, 2^64)");
  }
  const uint64_t s = seed.value_or(sim_.config().seed);
  finish_step("reset");
  sim_.reset(s);
  // every group forgets what it held of the old run (this one its armed pauses; the event stream
  // tells its subscribers)
  reset_groups_();
  reply->result = {{"seed", s}, {"time_s", sim_.time_s()}};
}

}  // namespace uavsim::server::api
