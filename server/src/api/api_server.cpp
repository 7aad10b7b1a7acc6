#include "api/api_server.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>

#include "api/request_fields.hpp"
#include "api/vehicle_arg.hpp"
#include "sim/checked_number.hpp"
#include "uavsim/common/shm_ring.hpp"

namespace uavsim::server::api {

namespace {

using Json = nlohmann::json;

constexpr auto kIdleWait = std::chrono::milliseconds(50);   // stop-check polling while held
constexpr auto kSeqPoll = std::chrono::milliseconds(1);     // MAVLink seq polling while a done waits

std::string dump(const Json& j) {
  return j.dump(-1, ' ', false, Json::error_handler_t::replace) + "\n";
}

// ranges of the numbers the built-in ops take
constexpr double kMaxRate = 1e6;            // set_rate: above this "as fast as possible" (0) is meant
constexpr double kMinRate = 1e-3;           // below, a control step would take minutes of wall time
constexpr double kMaxLockstepTimeout_s = 1e6;

Json error_reply(const Json& id, ApiError code, const std::string& message) {
  return Json{{"id", id},
              {"ok", false},
              {"error", {{"code", common::api_error_code(code)}, {"message", message}}}};
}

// compares secrets in time independent of where they differ
bool same_secret(const std::string& a, const std::string& b) {
  unsigned diff = a.size() == b.size() ? 0u : 1u;
  for (size_t i = 0; i < a.size(); ++i) diff |= static_cast<unsigned>(a[i] ^ b[i % (b.empty() ? 1 : b.size())]);
  return diff == 0 && !b.empty();
}

}  // namespace

ApiServer::ApiServer(sim::Simulation& sim, sim::Runner* runner, objects::ObjectSet objects,
                     const ApiConfig& config)
    : sim_(sim),
      runner_(runner),
      config_(config),
      vehicle_ops_(sim, std::move(objects)),
      lockstep_(sim.control_dt_s(), sim.physics_dt_s(), config.lockstep_timeout_s,
                [this] { return wall_clock_.now_s(); }),
      paused_(config.start_paused) {
  register_own_ops();
  add_group(&vehicle_ops_);
  LineServer::Callbacks cb;
  cb.on_connect = [this](uint64_t conn) {
    Json hello{{"hello", "uavsim"}, {"protocol", kProtocolVersion}, {"ops", ops_.names()}};
    if (config_.token) hello["auth_required"] = true;
    send(conn, hello);
    ++connections_;
  };
  cb.on_line = [this](uint64_t conn, std::string line) {
    // parse on the I/O thread; a malformed request's error is queued behind the requests before it, so
    // replies keep the order of the requests on the connection
    if (line.find_first_not_of(" \t") == std::string::npos) return;
    ParsedLine parsed = parse_request_line(line);
    if (parsed.error) {
      return reply_in_order(conn, error_reply(parsed.id, *parsed.error, parsed.error_message));
    }
    const Json& body = parsed.body;
    const Json& id = parsed.id;
    const std::string op = body["op"].get<std::string>();
    // --api-token-file: nothing is served before the token (an auth op, or a token field on a request)
    if (config_.token && !authenticated_.count(conn)) {
      const auto token = string_field(body, "token");
      if (!token || !same_secret(*token, *config_.token)) {
        return reply_in_order(
            conn, error_reply(id, ApiError::kUnauthorized,
                              token ? "wrong token" : "this server needs a token first: {\"op\":\"auth\",\"token\":...}"));
      }
      authenticated_.insert(conn);
    }
    const OpSpec* spec = ops_.find(op);
    if (spec == nullptr) return reply_in_order(conn, error_reply(id, ApiError::kUnknownOp, "unknown op '" + op + "'"));
    if (spec->thread == OpThread::kIo) {  // auth, the one op answered here
      return reply_in_order(conn,
                            Json{{"id", id}, {"ok", true}, {"result", {{"authenticated", config_.token.has_value()}}}});
    }
    enqueue({Request::Kind::kLine, conn, std::move(parsed.body)});
  };
  cb.on_line_too_long = [this](uint64_t conn) {
    reply_in_order(conn, error_reply(nullptr, ApiError::kLineTooLong, "request lines are limited to " +
                                                                  std::to_string(config_.max_line_bytes) +
                                                                  " bytes"));
  };
  cb.on_disconnect = [this](uint64_t conn) {
    authenticated_.erase(conn);
    --connections_;
    enqueue({Request::Kind::kDisconnect, conn, {}});
  };
  LineServer::Limits limits;
  limits.max_line_bytes = config_.max_line_bytes;
  limits.max_connections = config_.max_connections;
  limits.max_pending_bytes = config_.max_pending_bytes;
  limits.max_total_pending_bytes = config_.max_total_pending_bytes;
  limits.overload_line = dump(error_reply(nullptr, ApiError::kOverloaded,
                                          "the server's connection or reply-queue limit was reached; this "
                                          "connection is closed (read replies as they come, or connect later)"));
  server_ = std::make_unique<LineServer>(config_.bind_address, config_.port, limits, cb, config_.io_loop);
  shm_ = std::make_unique<ShmTransport>(*server_);
}

ApiServer::~ApiServer() { shutdown(); }

std::string ApiServer::peer_address(uint64_t conn) const { return server_->peer_address(conn); }

void ApiServer::start() {
  if (!frames_) FrameStream::register_unavailable(ops_);
  server_->start();
}

void ApiServer::set_seq_waiter(SeqWaiter* waiter) {
  seq_waiter_ = waiter;
  seq_processed_ = nullptr;
  if (waiter != nullptr) {
    seq_processed_ = [waiter](size_t vehicle, uint8_t seq) { return waiter->seq_processed(vehicle, seq); };
    waiter->set_progress_listener([this] {
      {
        std::lock_guard<std::mutex> lock(mutex_);
        ++seq_progress_;
      }
      wake_.notify_one();
    });
  }
}

void ApiServer::add_group(OpGroup* group) {
  group->register_ops(ops_);
  groups_.push_back(group);
}

void ApiServer::set_frame_service(render::FrameService* service) {
  if (service == nullptr) return;
  frames_ = std::make_unique<FrameStream>(sim_, *service, *server_,
                                          [this](uint64_t conn) { return lockstep_.joined(conn); });
  service->add_consumer(frames_.get());
  add_group(frames_.get());
}

void ApiServer::shutdown() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    shutdown_ = true;
  }
  wake_.notify_all();
  server_->stop();
}

void ApiServer::enqueue(Request request) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    queue_.push_back(std::move(request));
  }
  wake_.notify_all();
}

void ApiServer::send(uint64_t conn, const Json& message) { server_->send(conn, dump(message)); }

void ApiServer::reply_error(uint64_t conn, const Json& id, ApiError code,
                            const std::string& message) {
  reply(conn, error_reply(id, code, message));
}

void ApiServer::reply(uint64_t conn, const Json& message) {
  // a step's reply is deferred until its steps have run: the replies to the requests its connection
  // sent after it wait behind it, so that every connection gets its replies in request order
  if (step_reply_ && step_reply_->first == conn) {
    replies_behind_step_.push_back(message);
    return;
  }
  send(conn, message);
}

void ApiServer::finish_step(const char* by_op) {
  if (!step_reply_) return;
  const auto [conn, id] = *step_reply_;
  step_reply_.reset();
  if (by_op == nullptr) {
    send(conn, Json{{"id", id}, {"ok", true}, {"result", {{"time_s", sim_.time_s()}, {"paused", true}}}});
  } else {
    // another clock op took the clock: the step ends here, and says how far it got
    const uint64_t done = steps_requested_ - steps_remaining_;
    send(conn, error_reply(id, ApiError::kInterrupted,
                           std::string("a ") + by_op + " ended the step after " + std::to_string(done) + " of " +
                               std::to_string(steps_requested_) + " steps, at time_s " +
                               dump(Json(sim_.time_s()))));
    steps_remaining_ = 0;
  }
  for (const Json& held : replies_behind_step_) send(conn, held);
  replies_behind_step_.clear();
}

void ApiServer::reply_in_order(uint64_t conn, Json reply) {
  enqueue({Request::Kind::kReply, conn, std::move(reply)});
}

// ---------------------------------------------------------------------------------------------------
// the gate: requests, events, lockstep and pause, all on the loop thread before a control step

namespace {

// Holds the line server's and the shared-memory rings' wake-ups for one pass of the gate
// (LineServer::hold_wakeups): what the pass sends a connection leaves in one write, or wakes its
// ring's reader once. Released before the gate waits, and on leaving it.
class WakeupHold {
 public:
  WakeupHold(LineServer& server, ShmTransport& shm) : server_(&server), shm_(&shm) {
    server.hold_wakeups();
    shm.hold_wakeups();
  }
  ~WakeupHold() { release(); }
  WakeupHold(const WakeupHold&) = delete;
  WakeupHold& operator=(const WakeupHold&) = delete;
  void release() {
    if (server_ != nullptr) {
      server_->release_wakeups();
      shm_->release_wakeups();
    }
    server_ = nullptr;
  }

 private:
  LineServer* server_;
  ShmTransport* shm_;
};

}  // namespace

bool ApiServer::count_down_step() {
  if (steps_remaining_ > 0) {
    --steps_remaining_;
    return true;
  }
  if (step_reply_) finish_step();
  return false;
}

void ApiServer::on_gate() {
  for (;;) {
    // a pass of the gate is progress, though the clock is held (the watchdog tells it from a hang)
    sim_.schedule().activity().beat();
    WakeupHold hold(*server_, *shm_);
    // events before requests, so that a subscription's backlog and its stream neither overlap nor skip
    forward_events();
    drain();
    forward_events();
    // a pause armed with pause_at holds the clock from the first step at or after its time
    const double held_by_s = sim_.time_s() + 0.25 * sim_.physics_dt_s();
    if (!pause_at_s_.empty() && held_by_s >= *pause_at_s_.begin()) {
      paused_ = true;
      pause_at_s_.erase(pause_at_s_.begin(), pause_at_s_.upper_bound(held_by_s));
    }
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (shutdown_) return;
    }
    if (stop_check_ && stop_check_()) {
      // a stopping loop (or a caller whose gate must never hold, like the fuzz harness) still counts a
      // paused step down and answers it once done, with the replies held behind it: no reply is lost
      if (paused_ && !lockstep_.blocked()) count_down_step();
      return;
    }
    for (OpGroup* g : groups_) g->on_gate(send_fn_, in_lockstep_fn_);
    announce_ticks();
    uint64_t seq_progress_seen = 0;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      seq_progress_seen = seq_progress_;
    }
    lockstep_.complete(seq_processed_);

    bool waiting_seq = false;
    Clock::time_point next_deadline = Clock::now() + kIdleWait;
    if (lockstep_.blocked()) {
      // drop clients that let their tick time out (wall clock), then wait for the others
      for (const LockstepCoordinator::Dropped& d : lockstep_.expire(sim_.time_s())) {
        lockstep_left(d.last_left_at_s);
        send(d.conn, Json{{"event", "lockstep_dropped"}, {"reason", "timeout"}, {"time", sim_.time_s()}});
      }
      if (!lockstep_.blocked()) continue;
      const double until_deadline_s = std::max(0.0, *lockstep_.deadline_s() - wall_clock_.now_s());
      if (until_deadline_s < std::chrono::duration<double>(kIdleWait).count()) {
        next_deadline = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                           std::chrono::duration<double>(until_deadline_s));
      }
      waiting_seq = lockstep_.waiting_on_seq();
    } else if (!paused_) {
      return;
    } else if (count_down_step()) {
      return;
    }
    hold.release();
    // wait for a request (or a lockstep deadline, or the next MAVLink seq poll)
    // (the endpoint's progress call wakes a seq wait at once; the poll is the fallback for a waiter
    // that makes none)
    std::unique_lock<std::mutex> lock(mutex_);
    if (queue_.empty() && !shutdown_ && !(waiting_seq && seq_progress_ != seq_progress_seen)) {
      wake_.wait_until(lock, waiting_seq ? std::min(next_deadline, Clock::now() + kSeqPoll) : next_deadline,
                       [&] {
                         return !queue_.empty() || shutdown_ ||
                                (waiting_seq && seq_progress_ != seq_progress_seen);
                       });
    }
  }
}

void ApiServer::drain() {
  std::deque<Request> batch;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    batch.swap(queue_);
  }
  for (Request& r : batch) {
    switch (r.kind) {
      case Request::Kind::kDisconnect:
        if (step_reply_ && step_reply_->first == r.conn) {
          step_reply_.reset();
          replies_behind_step_.clear();
        }
        lockstep_left(lockstep_.leave(r.conn, sim_.time_s()));
        event_subscribers_.erase(r.conn);
        for (OpGroup* g : groups_) g->on_disconnect(r.conn);
        shm_->on_disconnect(r.conn);
        // every request of the connection has been answered: the socket may go once that is written
        server_->close_when_sent(r.conn);
        break;
      case Request::Kind::kLine:
        handle(r.conn, r.body);
        break;
      case Request::Kind::kReply:
        reply(r.conn, r.body);
        break;
    }
  }
}

void ApiServer::forward_events() {
  const sim::EventLog& log = sim_.events();
  if (events_forwarded_ > log.next_seq()) events_forwarded_ = 0;  // the log was cleared (reset)
  // events_forwarded_ is a seq; the log holds first_seq() onwards (called every step, so none is missed)
  for (const sim::Event& event : log.recent()) {
    if (event.seq < events_forwarded_) continue;
    const Json e = event_json(event);
    for (uint64_t conn : event_subscribers_) send(conn, e);
  }
  events_forwarded_ = log.next_seq();
}

void ApiServer::announce_ticks() {
  const double now = sim_.time_s();
  const std::vector<uint64_t> due = lockstep_.due(now);
  // the MAVLink bytes of the control steps before this tick reach the client before the tick
  if (!due.empty() && seq_waiter_ != nullptr) seq_waiter_->flush_sent();
  for (uint64_t conn : due) {
    // what else is due at this tick (the frames) reaches the client before the tick (docs/protocol.md)
    for (OpGroup* g : groups_) g->before_tick(conn, send_fn_);
    const int64_t tick = lockstep_.begin_tick(conn, now);
    // on a shared-memory stream: one binary record with the tick's radio frames
    if (!shm_->send_tick(conn, tick, now))
      send(conn, Json{{"event", "tick"}, {"tick", tick}, {"time", now}});
  }
}

void ApiServer::lockstep_left(std::optional<double> last_at_s) {
  // pause_at lockstep_empty: the last client's tick is the same sim time in every run, whenever its
  // leaving is noticed
  if (!last_at_s || !pause_when_lockstep_empty_) return;
  pause_at_s_.insert(*last_at_s);
  pause_when_lockstep_empty_ = false;
}

// ---------------------------------------------------------------------------------------------------
// requests

Json ApiServer::event_json(const sim::Event& e) const {
  return Json{{"event", "sim_event"},
              {"seq", e.seq},
              {"time", e.time_s},
              {"type", sim::event_type_name(e.type)},
              {"vehicle", e.vehicle},
              {"vehicle_name", e.vehicle >= 0 && static_cast<size_t>(e.vehicle) < sim_.vehicle_count()
                                   ? Json(sim_.vehicle_name(static_cast<size_t>(e.vehicle)))
                                   : Json(nullptr)},
              {"detail", e.detail}};
}

void ApiServer::handle(uint64_t conn, const Json& request) {
  const Json id = request.contains("id") ? request["id"] : Json(nullptr);
  const std::string op = request["op"].get<std::string>();  // checked on the I/O thread
  const OpSpec* spec = ops_.find(op);                       // likewise: the op is in the table
  if (const auto bad = mistyped_field(request, spec->typed_fields)) return reply_error(conn, id, ApiError::kBadField, *bad);
  OpReply reply;
  // the watchdog names the op a stuck loop is in
  sim::LoopActivity& trail = sim_.schedule().activity();
  trail.set_detail(spec->name.c_str());
  spec->handler(conn, request, &reply);
  trail.set_detail(nullptr);
  if (reply.failed()) return reply_error(conn, id, *reply.error, reply.message);
  if (!reply.deferred) this->reply(conn, Json{{"id", id}, {"ok", true}, {"result", reply.result}});
}

// ---------------------------------------------------------------------------------------------------
// this server's own ops: the clock, events and lockstep

void ApiServer::register_own_ops() {
  using Member = void (ApiServer::*)(uint64_t, const Json&, OpReply*);
  const auto add = [this](const char* name, const char* group, Member op) {
    ops_.add({name, group, std::bind_front(op, this), core_op_fields()});
  };
  add("status", "clock", &ApiServer::op_status);
  add("pause", "clock", &ApiServer::op_pause);
  add("pause_at", "clock", &ApiServer::op_pause_at);
  add("resume", "clock", &ApiServer::op_resume);
  add("step", "clock", &ApiServer::op_step);
  add("set_rate", "clock", &ApiServer::op_set_rate);
  add("reset", "clock", &ApiServer::op_reset);
  add("events", "events", &ApiServer::op_events);
  add("subscribe_events", "events", &ApiServer::op_subscribe_events);
  add("unsubscribe_events", "events", &ApiServer::op_unsubscribe_events);
  add("lockstep_join", "lockstep", &ApiServer::op_lockstep_join);
  add("lockstep_leave", "lockstep", &ApiServer::op_lockstep_leave);
  add("done", "lockstep", &ApiServer::op_done);
  add("lockstep_shm", "lockstep", &ApiServer::op_lockstep_shm);
  // answered by the transport on the I/O thread (--api-token-file), before any request is queued
  ops_.add({"auth", "connection", nullptr, {}, OpThread::kIo});
}

void ApiServer::op_status(uint64_t, const Json&, OpReply* reply) {
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

void ApiServer::op_pause(uint64_t, const Json&, OpReply* reply) {
  finish_step("pause");
  paused_ = true;
  reply->result = {{"time_s", sim_.time_s()}, {"paused", true}};
}

void ApiServer::op_pause_at(uint64_t, const Json& request, OpReply* reply) {
  // arm a pause at a sim time and/or when the last lockstep client leaves (deterministic ends)
  const auto at = number_field(request, "time_s");
  const bool empty = request.value("lockstep_empty", false);
  if (!at && !empty) return reply->fail(ApiError::kMissingField, "\"time_s\" or \"lockstep_empty\": true is required");
  if (at && !std::isfinite(*at)) return reply->fail(ApiError::kBadField, "\"time_s\" must be a finite sim time");
  if (at) pause_at_s_.insert(*at);
  if (empty) pause_when_lockstep_empty_ = true;
  reply->result = {{"time_s", sim_.time_s()},
                   {"pause_at_s", Json(std::vector<double>(pause_at_s_.begin(), pause_at_s_.end()))},
                   {"lockstep_empty", pause_when_lockstep_empty_}};
}

void ApiServer::op_resume(uint64_t, const Json&, OpReply* reply) {
  finish_step("resume");
  paused_ = false;
  steps_remaining_ = 0;
  reply->result = {{"time_s", sim_.time_s()}, {"paused", false}};
}

void ApiServer::op_step(uint64_t conn, const Json& request, OpReply* reply) {
  // N control steps (default 1) or a duration rounded to whole control steps; pauses first
  const auto steps = number_field(request, "steps");
  const auto duration = number_field(request, "duration_s");
  double n = 1;
  if (steps) n = *steps;
  if (duration) n = std::round(*duration / sim_.control_dt_s());
  if (!(n >= 1 && n <= 1e9) || std::floor(n) != n) {
    return reply->fail(ApiError::kBadField,
                       "\"steps\" must be an integer in [1, 1e9] (or \"duration_s\" at least one control step)");
  }
  if (step_reply_) return reply->fail(ApiError::kBusy, "another step request is in progress");
  paused_ = true;
  steps_remaining_ = static_cast<uint64_t>(n);
  steps_requested_ = steps_remaining_;
  step_reply_ = std::make_pair(conn, request.contains("id") ? request["id"] : Json(nullptr));
  reply->deferred = true;  // answered when the steps are done
}

void ApiServer::op_set_rate(uint64_t, const Json& request, OpReply* reply) {
  const auto rate = number_field(request, "rate");
  if (!rate) {
    return reply->fail(ApiError::kMissingField, "\"rate\" (a number: 1 = real time, 0 = as fast as possible) is required");
  }
  if (*rate != 0.0 && !sim::finite_in(*rate, kMinRate, kMaxRate)) {
    return reply->fail(ApiError::kBadField, "\"rate\" must be 0 (as fast as possible) or in [0.001, 1e6]");
  }
  if (runner_ == nullptr) return reply->fail(ApiError::kNotAvailable, "this server has no clock runner");
  runner_->set_rate(*rate);
  reply->result = {{"rate", *rate}};
}

void ApiServer::op_reset(uint64_t, const Json& request, OpReply* reply) {
  // an integer seed travels exactly; a number in double form must be a whole one below 2^64
  const auto it = request.find("seed");
  std::optional<uint64_t> seed;
  if (it != request.end()) {
    seed = it->is_number_unsigned() ? std::optional<uint64_t>(it->get<uint64_t>())
                                    : sim::checked_integer<uint64_t>(it->get<double>());
  }
  if (it != request.end() && !seed) return reply->fail(ApiError::kBadField, "\"seed\" must be an integer in [0, 2^64)");
  const uint64_t s = seed.value_or(sim_.config().seed);
  finish_step("reset");
  sim_.reset(s);
  events_forwarded_ = 0;
  pause_at_s_.clear();
  pause_when_lockstep_empty_ = false;
  for (OpGroup* g : groups_) g->on_reset();
  lockstep_.reset();
  for (uint64_t conn : event_subscribers_) send(conn, Json{{"event", "reset"}, {"seed", s}});
  reply->result = {{"seed", s}, {"time_s", sim_.time_s()}};
}

void ApiServer::op_events(uint64_t, const Json& request, OpReply* reply) {
  const auto from_number = number_field(request, "from_seq");
  const auto from = from_number ? sim::checked_integer<uint64_t>(*from_number) : std::optional<uint64_t>(0);
  if (!from) return reply->fail(ApiError::kBadField, "\"from_seq\" must be a non-negative integer");
  // the events already forwarded (later ones stream to subscribers), from from_seq or the oldest
  // still held: first_seq > from_seq tells the client that the ones between were dropped
  const uint64_t from_seq = *from;
  const sim::EventLog& log = sim_.events();
  Json list = Json::array();
  for (const sim::Event& e : log.recent()) {
    if (e.seq >= from_seq && e.seq < events_forwarded_) list.push_back(event_json(e));
  }
  const uint64_t first_seq = std::min<uint64_t>(log.first_seq(), events_forwarded_);
  reply->result = {{"events", list}, {"first_seq", first_seq}, {"next_seq", events_forwarded_}};
}

void ApiServer::op_subscribe_events(uint64_t conn, const Json& request, OpReply* reply) {
  // a subscriber gets the backlog in the reply; later events stream as {"event": "sim_event", ...}
  op_events(conn, request, reply);
  if (!reply->failed()) event_subscribers_.insert(conn);
}

void ApiServer::op_unsubscribe_events(uint64_t conn, const Json&, OpReply*) { event_subscribers_.erase(conn); }

void ApiServer::op_lockstep_join(uint64_t conn, const Json& request, OpReply* reply) {
  const auto period = number_field(request, "period_s");
  const auto timeout = number_field(request, "timeout_s");
  if (!period) return reply->fail(ApiError::kMissingField, "\"period_s\" (sim seconds between ticks) is required");
  if (!(*period > 0.0) || !std::isfinite(*period) || *period > 3600.0) {
    return reply->fail(ApiError::kBadField, "\"period_s\" must be in (0, 3600]");
  }
  if (timeout && !(*timeout > 0.0 && *timeout <= kMaxLockstepTimeout_s)) {
    // the protocol's range: a deadline further out is no different from none
    return reply->fail(ApiError::kBadField, "\"timeout_s\" must be in (0, 1e6]");
  }
  // the first tick is the next multiple of the period at or after now; strictly after now for a
  // connection whose output of now was prepared before it joined (a camera subscriber: the frame due
  // at a tick must have been captured for a lockstep client)
  const bool after_now = std::any_of(groups_.begin(), groups_.end(),
                                     [&](const OpGroup* g) { return g->prepared_before_join(conn); });
  const double from_s = sim_.time_s() + (after_now ? 0.5 * sim_.control_dt_s() : 0.0);
  const LockstepCoordinator::Joined joined = lockstep_.join(conn, *period, timeout, from_s);
  reply->result = {{"period_s", joined.period_s},
                   {"first_tick_time", joined.first_tick_time_s},
                   {"timeout_s", joined.timeout_s}};
}

void ApiServer::op_lockstep_leave(uint64_t conn, const Json&, OpReply*) {
  lockstep_left(lockstep_.leave(conn, sim_.time_s()));
}

void ApiServer::op_done(uint64_t conn, const Json& request, OpReply* reply) {
  const auto tick = number_field(request, "tick");  // a number when present (core_op_fields)
  const auto busy = number_field(request, "busy_until");
  auto seqs = request.find("mavlink_seq");
  std::string message;
  if (const auto refused = lockstep_.check_done(conn, tick, &message)) {
    return reply->fail(*refused, std::move(message));
  }
  if (has_field(request, "busy_until") && (!busy || !std::isfinite(*busy))) {
    return reply->fail(ApiError::kBadField, "\"busy_until\" must be a sim time in seconds");
  }
  if (seqs != request.end() && !seqs->is_object()) {
    return reply->fail(ApiError::kBadField, "\"mavlink_seq\" must be an object {vehicle: seq}");
  }
  std::map<size_t, uint8_t> wait;
  if (seqs != request.end()) {
    for (auto it = seqs->begin(); it != seqs->end(); ++it) {
      Json probe = {{"vehicle", it.key()}};
      // "0" names vehicle 0; any other string a vehicle name
      char* end = nullptr;
      const long index = std::strtol(it.key().c_str(), &end, 10);
      if (!it.key().empty() && *end == '\0') probe["vehicle"] = index;
      const auto v = required_vehicle(sim_, probe, reply);
      if (!v) return;
      if (!it.value().is_number_integer() || it.value().get<int64_t>() < 0 || it.value().get<int64_t>() > 255) {
        return reply->fail(ApiError::kBadField, "MAVLink sequence numbers are integers in [0, 255]");
      }
      wait[*v] = static_cast<uint8_t>(it.value().get<int64_t>());
    }
  }
  const int64_t done_tick = lockstep_.take_done(conn, busy, std::move(wait));
  reply->result = {{"tick", done_tick}, {"mavlink_seq_checked", seq_waiter_ != nullptr}};
}

void ApiServer::op_lockstep_shm(uint64_t conn, const Json& request, OpReply* reply) {
  // only for a client on this machine, once, and not behind a step's reply (which must come on TCP)
  if (!config_.shm) {
    return reply->fail(ApiError::kNotAvailable, "this server serves no shared-memory stream");
  }
  const std::string peer = server_->peer_address(conn);
  if (peer.rfind("127.", 0) != 0) {
    return reply->fail(ApiError::kNotAvailable,
                       "the shared-memory stream is for clients on the server's machine; "
                       "this one connects from " +
                           peer);
  }
  if (shm_->attached(conn))
    return reply->fail(ApiError::kBadState,
                       "this connection is on the shared-memory stream already");
  if (step_reply_ && step_reply_->first == conn) {
    return reply->fail(ApiError::kBusy, "a step request of this connection is in progress");
  }
  const auto bytes = number_field(request, "ring_bytes");
  const auto ring_bytes = bytes ? sim::checked_integer<uint64_t>(*bytes)
                                : std::optional<uint64_t>(ShmTransport::kDefaultRingBytes);
  if (!ring_bytes || common::shm::region_bytes(static_cast<size_t>(*ring_bytes)) == 0) {
    return reply->fail(ApiError::kBadField,
                       "\"ring_bytes\" must be a power of two in [65536, 268435456]");
  }
  std::string why;
  const auto offer = shm_->offer(conn, static_cast<size_t>(*ring_bytes), &why);
  if (!offer) return reply->fail(ApiError::kNotAvailable, "no shared-memory stream: " + why);
  // the reply is the last message on TCP; everything after it goes to the ring
  const Json id = request.contains("id") ? request["id"] : Json(nullptr);
  send(conn, Json{{"id", id}, {"ok", true}, {"result", *offer}});
  shm_->activate(conn);
  reply->deferred = true;
}

}  // namespace uavsim::server::api
