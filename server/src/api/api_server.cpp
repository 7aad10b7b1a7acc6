#include "api/api_server.hpp"

#include <algorithm>
#include <functional>

#include "api/binary_requests.hpp"
#include "api/request_fields.hpp"

namespace uavsim::server::api {

namespace {

using Json = nlohmann::json;

constexpr auto kIdleWait = std::chrono::milliseconds(50);  // stop-check polling while held
constexpr auto kSeqPoll = std::chrono::milliseconds(1);    // MAVLink seq polling while a done waits

std::string dump(const Json& j) {
  return j.dump(-1, ' ', false, Json::error_handler_t::replace) + "\n";
}

// compares secrets in time independent of where they differ
bool same_secret(const std::string& a, const std::string& b) {
  unsigned diff = a.size() == b.size() ? 0u : 1u;
  for (size_t i = 0; i < a.size(); ++i)
    diff |= static_cast<unsigned>(a[i] ^ b[i % (b.empty() ? 1 : b.size())]);
  return diff == 0 && !b.empty();
}

}  // namespace

ApiServer::ApiServer(sim::Simulation& sim, sim::Runner* runner, objects::ObjectSet objects,
                     const ApiConfig& config)
    : sim_(sim),
      runner_(runner),
      config_(config),
      lockstep_(sim.control_dt_s(), sim.physics_dt_s(), config.lockstep_timeout_s,
                [this] { return wall_clock_.now_s(); }),
      vehicle_ops_(sim, std::move(objects)) {
  LineServer::Callbacks cb;
  cb.on_connect = [this](uint64_t conn) {
    Json hello{{"hello", "uavsim"}, {"protocol", kProtocolVersion}, {"ops", ops_.names()}};
    if (config_.token) hello["auth_required"] = true;
    send(conn, hello);
    ++connections_;
  };
  cb.on_line = [this](uint64_t conn, std::string line) {
    // parse on the I/O thread; a malformed request's error is queued behind the requests before it,
    // so replies keep the order of the requests on the connection
    if (line.find_first_not_of(" \t") == std::string::npos) return;
    ParsedLine parsed = parse_request_line(line);
    if (parsed.error) {
      return reply_in_order(conn, error_reply(parsed.id, *parsed.error, parsed.error_message));
    }
    const Json& body = parsed.body;
    const Json& id = parsed.id;
    const std::string op = body["op"].get<std::string>();
    // --api-token-file: nothing is served before the token (an auth op, or a token field on a
    // request)
    if (config_.token && !authenticated_.count(conn)) {
      const auto token = string_field(body, "token");
      if (!token || !same_secret(*token, *config_.token)) {
        return reply_in_order(
            conn, error_reply(
                      id, ApiError::kUnauthorized,
                      token ? "wrong token"
                            : "this server needs a token first: {\"op\":\"auth\",\"token\":...}"));
      }
      authenticated_.insert(conn);
    }
    const OpSpec* spec = ops_.find(op);
    if (spec == nullptr)
      return reply_in_order(conn, error_reply(id, ApiError::kUnknownOp, "unknown op '" + op + "'"));
    if (spec->thread == OpThread::kIo) {  // auth, the one op answered here
      return reply_in_order(conn, ok_reply(id, {{"authenticated", config_.token.has_value()}}));
    }
    enqueue({Request::Kind::kLine, conn, std::move(parsed.body)});
  };
  cb.on_record = [this](uint64_t conn, uint16_t type, std::span<const uint8_t> payload) {
    on_binary_request(conn, type, payload);
  };
  cb.on_line_too_long = [this](uint64_t conn) {
    reply_in_order(conn, error_reply(nullptr, ApiError::kLineTooLong,
                                     "request lines are limited to " +
                                         std::to_string(config_.max_line_bytes) + " bytes"));
  };
  cb.on_disconnect = [this](uint64_t conn) {
    authenticated_.erase(conn);
    --connections_;
    enqueue({Request::Kind::kDisconnect, conn, {}});
    flush_staged();
  };
  cb.on_read_end = [this](uint64_t) { flush_staged(); };
  LineServer::Limits limits;
  limits.max_line_bytes = config_.max_line_bytes;
  limits.max_connections = config_.max_connections;
  limits.max_pending_bytes = config_.max_pending_bytes;
  limits.max_total_pending_bytes = config_.max_total_pending_bytes;
  limits.overload_line =
      dump(error_reply(nullptr, ApiError::kOverloaded,
                       "the server's connection or reply-queue limit was reached; this "
                       "connection is closed (read replies as they come, or connect later)"));
  server_ =
      std::make_unique<LineServer>(config_.bind_address, config_.port, limits, cb, config_.io_loop);
  shm_ = std::make_unique<ShmTransport>(*server_);

  // the server's own groups first (the hello lists their ops first), then the vehicles'
  clock_ops_ =
      std::make_unique<ClockOps>(sim_, runner_, lockstep_, config_.start_paused, send_fn_, [this] {
        for (OpGroup* g : groups_) g->on_reset();
      });
  event_ops_ = std::make_unique<EventOps>(sim_, send_fn_);
  LockstepOps::Server around;
  around.send = send_fn_;
  around.peer_address = [this](uint64_t conn) { return server_->peer_address(conn); };
  around.prepared_before_join = [this](uint64_t conn) {
    return std::any_of(groups_.begin(), groups_.end(),
                       [&](const OpGroup* g) { return g->prepared_before_join(conn); });
  };
  around.seq_checked = [this] { return seq_waiter_ != nullptr; };
  around.serve_query = [this](uint64_t conn, const Json& request) {
    return serve_query(conn, request);
  };
  lockstep_ops_ = std::make_unique<LockstepOps>(
      sim_, lockstep_, *clock_ops_, config_.shm ? shm_.get() : nullptr, std::move(around));
  add_group(clock_ops_.get());
  add_group(event_ops_.get());
  add_group(lockstep_ops_.get());
  // answered by the transport on the I/O thread (--api-token-file), before any request is queued
  ops_.add({"auth", "connection", nullptr, {}, OpThread::kIo});
  add_group(&vehicle_ops_);
}

ApiServer::~ApiServer() { shutdown(); }

void ApiServer::on_binary_request(uint64_t conn, uint16_t type, std::span<const uint8_t> payload) {
  // served as the JSON request it stands for, answered only if refused (docs/protocol.md)
  std::string why;
  auto body = binary_request_json(type, payload, &why);
  if (!body) return reply_in_order(conn, error_reply(nullptr, ApiError::kBadRequest, why));
  const Json id = body->value("id", Json(nullptr));
  if (config_.token && !authenticated_.count(conn)) {
    return reply_in_order(conn, error_reply(id, ApiError::kUnauthorized,
                                            "this server needs a token first: {\"op\":\"auth\","
                                            "\"token\":...} on the ring or TCP"));
  }
  // a server without a radio serves no radio_send
  const std::string op = (*body)["op"].get<std::string>();
  if (ops_.find(op) == nullptr)
    return reply_in_order(conn, error_reply(id, ApiError::kUnknownOp, "unknown op '" + op + "'"));
  enqueue({Request::Kind::kLine, conn, std::move(*body), /*errors_only=*/true});
}

std::string ApiServer::peer_address(uint64_t conn) const { return server_->peer_address(conn); }

void ApiServer::start() {
  if (!frames_) FrameStream::register_unavailable(ops_);
  server_->start();
}

void ApiServer::set_seq_waiter(SeqWaiter* waiter) {
  seq_waiter_ = waiter;
  seq_processed_ = nullptr;
  if (waiter != nullptr) {
    seq_processed_ = [waiter](size_t vehicle, uint8_t seq) {
      return waiter->seq_processed(vehicle, seq);
    };
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
  shm_->end_quiet_all();  // no tick comes any more
  server_->stop();
}

void ApiServer::enqueue(Request request) { staged_.push_back(std::move(request)); }

void ApiServer::flush_staged() {
  if (staged_.empty()) return;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    for (Request& r : staged_) queue_.push_back(std::move(r));
  }
  staged_.clear();
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
  if (clock_ops_->hold_reply(conn, message)) return;
  send(conn, message);
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

void ApiServer::on_gate() {
  for (;;) {
    // a pass of the gate is progress, though the clock is held (the watchdog tells it from a hang)
    sim_.schedule().activity().beat();
    WakeupHold hold(*server_, *shm_);
    // events before requests, so that a subscription's backlog and its stream neither overlap nor
    // skip
    event_ops_->forward();
    drain();
    event_ops_->forward();
    clock_ops_->arm_due_pauses();
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (shutdown_) return;
    }
    if (stop_check_ && stop_check_()) {
      shm_->end_quiet_all();  // no tick may come any more
      // a stopping loop (or a caller whose gate must never hold, like the fuzz harness) still
      // counts a paused step down and answers it once done, with the replies held behind it: no
      // reply is lost
      if (clock_ops_->paused() && !lockstep_.blocked()) clock_ops_->count_down_step();
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
        clock_ops_->lockstep_left(d.last_left_at_s);
        shm_->end_quiet(d.conn);  // its drop wakes it (a done waiting on MAVLink seqs was quiet)
        send(d.conn,
             Json{{"event", "lockstep_dropped"}, {"reason", "timeout"}, {"time", sim_.time_s()}});
      }
      if (!lockstep_.blocked()) continue;
      const double until_deadline_s = std::max(0.0, *lockstep_.deadline_s() - wall_clock_.now_s());
      if (until_deadline_s < std::chrono::duration<double>(kIdleWait).count()) {
        next_deadline = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                           std::chrono::duration<double>(until_deadline_s));
      }
      waiting_seq = lockstep_.waiting_on_seq();
    } else if (!clock_ops_->paused()) {
      return;
    } else if (clock_ops_->count_down_step()) {
      return;
    } else {
      // the clock idles paused: no tick comes before a resume or a step, so a client quiet since
      // its done is woken for what it has now (its replies, the events of the pause) rather than
      // left with them for as long as the pause lasts
      shm_->end_quiet_all();
    }
    hold.release();
    // wait for a request (or a lockstep deadline, or the next MAVLink seq poll)
    // (the endpoint's progress call wakes a seq wait at once; the poll is the fallback for a waiter
    // that makes none)
    std::unique_lock<std::mutex> lock(mutex_);
    if (queue_.empty() && !shutdown_ && !(waiting_seq && seq_progress_ != seq_progress_seen)) {
      wake_.wait_until(
          lock, waiting_seq ? std::min(next_deadline, Clock::now() + kSeqPoll) : next_deadline,
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
    // a request after a done (or its error reply) ends the connection's quiet: its reply may be
    // awaited (ShmTransport::quiet_until_tick)
    if (r.kind != Request::Kind::kDisconnect) shm_->end_quiet(r.conn);
    switch (r.kind) {
      case Request::Kind::kDisconnect:
        // the clock's group drops the connection's step first, lockstep stops waiting for it
        for (OpGroup* g : groups_) g->on_disconnect(r.conn);
        shm_->on_disconnect(r.conn);
        // every request of the connection has been answered: the socket may go once that is written
        server_->close_when_sent(r.conn);
        break;
      case Request::Kind::kLine:
        handle(r.conn, r.body, r.errors_only);
        break;
      case Request::Kind::kReply:
        reply(r.conn, r.body);
        break;
    }
  }
}

void ApiServer::announce_ticks() {
  const double now = sim_.time_s();
  const std::vector<uint64_t> due = lockstep_.due(now);
  // the MAVLink bytes of the control steps before this tick reach the client before the tick
  if (!due.empty() && seq_waiter_ != nullptr) seq_waiter_->flush_sent();
  for (uint64_t conn : due) {
    // what else is due at this tick (the frames) reaches the client before the tick
    // (docs/protocol.md)
    for (OpGroup* g : groups_) g->before_tick(conn, send_fn_);
    const int64_t tick = lockstep_.begin_tick(conn, now);
    // on a shared-memory stream: one binary record with the tick's radio frames
    if (!shm_->send_tick(conn, tick, now))
      send(conn, Json{{"event", "tick"}, {"tick", tick}, {"time", now}});
  }
}

// ---------------------------------------------------------------------------------------------------
// requests

OpReply ApiServer::run_op(uint64_t conn, const OpSpec& spec, const Json& request) {
  OpReply reply;
  if (const auto bad = mistyped_field(request, spec.typed_fields)) {
    reply.fail(ApiError::kBadField, *bad);
    return reply;
  }
  // the watchdog names the op a stuck loop is in
  sim::LoopActivity& trail = sim_.schedule().activity();
  trail.set_detail(spec.name.c_str());
  spec.handler(conn, request, &reply);
  trail.set_detail(nullptr);
  return reply;
}

Json ApiServer::serve_query(uint64_t conn, const Json& request) {
  const OpSpec* spec = ops_.find(request.value("op", std::string()));
  if (spec == nullptr || spec->handler == nullptr) {
    return {{"error", error_reply(nullptr, ApiError::kUnknownOp, "unknown op")["error"]}};
  }
  OpReply reply = run_op(conn, *spec, request);
  if (reply.failed())
    return {{"error", error_reply(nullptr, *reply.error, reply.message)["error"]}};
  return {{"result", std::move(reply.result)}};
}

void ApiServer::handle(uint64_t conn, const Json& request, bool errors_only) {
  const Json id = request.contains("id") ? request["id"] : Json(nullptr);
  const std::string op = request["op"].get<std::string>();  // checked on the I/O thread
  const OpSpec* spec = ops_.find(op);                       // likewise: the op is in the table
  OpReply reply = run_op(conn, *spec, request);
  if (reply.failed()) return reply_error(conn, id, *reply.error, reply.message);
  if (!reply.deferred && !errors_only) this->reply(conn, ok_reply(id, std::move(reply.result)));
}

}  // namespace uavsim::server::api
