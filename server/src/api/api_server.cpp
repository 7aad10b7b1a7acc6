#include "api/api_server.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "api/request_fields.hpp"
#include "sim/checked_number.hpp"

namespace uavsim::server::api {

namespace {

using Json = nlohmann::json;

constexpr auto kIdleWait = std::chrono::milliseconds(50);   // stop-check polling while held
constexpr auto kSeqPoll = std::chrono::milliseconds(1);     // MAVLink seq polling while a done waits

const char* const kOps[] = {"status",        "pause",           "resume",         "step",
                            "set_rate",      "reset",           "vehicles",       "truck",
                            "balloons",      "events",          "subscribe_events", "unsubscribe_events",
                            "kill_vehicle",  "motor_failure",   "gps_glitch",     "gps_denied",
                            "link_drop",     "gimbal",          "lockstep_join",  "lockstep_leave",
                            "done",          "camera_list",     "camera_subscribe", "camera_unsubscribe",
                            "camera_blackout", "wind",       "pause_at"};

Json vec3(const Eigen::Vector3d& v) { return Json::array({v.x(), v.y(), v.z()}); }

std::string dump(const Json& j) {
  return j.dump(-1, ' ', false, Json::error_handler_t::replace) + "\n";
}

// The fields the built-in ops read, with their types: a request naming one with another type gets
// bad_field before its op runs (so no op half-applies a request). Extensions check their own.
constexpr FieldSpec kBuiltinFields[] = {
    {"steps", FieldType::kNumber},       {"duration_s", FieldType::kNumber},
    {"rate", FieldType::kNumber},        {"seed", FieldType::kNumber},
    {"from_seq", FieldType::kNumber},    {"vehicle", FieldType::kIndexOrName},
    {"reason", FieldType::kString},      {"rotor", FieldType::kNumber},
    {"failed", FieldType::kBoolean},     {"offset_enu_m", FieldType::kArray},
    {"denied", FieldType::kBoolean},     {"down", FieldType::kBoolean},
    {"gimbal", FieldType::kString},      {"mode", FieldType::kString},
    {"pitch_deg", FieldType::kNumber},   {"yaw_deg", FieldType::kNumber},
    {"period_s", FieldType::kNumber},    {"timeout_s", FieldType::kNumber},
    {"tick", FieldType::kNumber},        {"busy_until", FieldType::kNumber},
    {"mavlink_seq", FieldType::kObject},
    {"speed_m_s", FieldType::kNumber},   {"from_deg", FieldType::kNumber},
    {"turbulence_sd_m_s", FieldType::kNumber}, {"gust_m_s", FieldType::kNumber},
    {"gust_duration_s", FieldType::kNumber},
    {"time_s", FieldType::kNumber},      {"lockstep_empty", FieldType::kBoolean},
};

// ranges of the numbers the built-in ops take
constexpr double kMaxRate = 1e6;            // set_rate: above this "as fast as possible" (0) is meant
constexpr double kMinRate = 1e-3;           // below, a control step would take minutes of wall time
constexpr double kMaxLockstepTimeout_s = 1e6;
constexpr double kMaxGlitch_m = 1e5;
constexpr double kMaxGimbalAngle_deg = 360.0;

Json error_reply(const Json& id, const std::string& code, const std::string& message) {
  return Json{{"id", id}, {"ok", false}, {"error", {{"code", code}, {"message", message}}}};
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
    : sim_(sim), runner_(runner), objects_(std::move(objects)), config_(config), paused_(config.start_paused) {
  LineServer::Callbacks cb;
  cb.on_connect = [this](uint64_t conn) {
    Json ops = Json::array();
    for (const char* op : kOps) ops.push_back(op);
    for (const std::string& op : extension_ops_) ops.push_back(op);
    ops.push_back("auth");
    Json hello{{"hello", "uavsim"}, {"protocol", kProtocolVersion}, {"ops", ops}};
    if (config_.token) hello["auth_required"] = true;
    send(conn, hello);
    ++connections_;
    enqueue({Request::Kind::kConnect, conn, {}});
  };
  cb.on_line = [this](uint64_t conn, std::string line) {
    // parse on the I/O thread; a malformed request's error is queued behind the requests before it, so
    // replies keep the order of the requests on the connection
    if (line.find_first_not_of(" \t") == std::string::npos) return;
    ParsedLine parsed = parse_request_line(line);
    if (!parsed.error_code.empty()) {
      return reply_in_order(conn, error_reply(parsed.id, parsed.error_code, parsed.error_message));
    }
    Json& body = parsed.body;
    const Json& id = parsed.id;
    const std::string op = body["op"].get<std::string>();
    // --api-token-file: nothing is served before the token (an auth op, or a token field on a request)
    if (config_.token && !authenticated_.count(conn)) {
      const auto token = string_field(body, "token");
      if (!token || !same_secret(*token, *config_.token)) {
        return reply_in_order(
            conn, error_reply(id, "unauthorized",
                              token ? "wrong token" : "this server needs a token first: {\"op\":\"auth\",\"token\":...}"));
      }
      authenticated_.insert(conn);
    }
    if (op == "auth") {
      return reply_in_order(conn,
                            Json{{"id", id}, {"ok", true}, {"result", {{"authenticated", config_.token.has_value()}}}});
    }
    // gcs_link_open sends UDP datagrams: only to the requesting client's own host, unless allowed
    if (op == "gcs_link_open" && !config_.allow_remote_gcs) {
      const std::string peer = server_->peer_address(conn);
      auto host = body.find("gcs_target_host");
      if (host == body.end()) {
        body["gcs_target_host"] = peer;
      } else if (host->is_string() && host->get<std::string>() != peer) {
        return reply_in_order(conn, error_reply(id, "forbidden",
                                                "gcs_target_host must be this client's own address (" + peer +
                                                    ") unless the server runs with --allow-remote-gcs"));
      }
    }
    if (std::find_if(std::begin(kOps), std::end(kOps), [&](const char* o) { return op == o; }) ==
            std::end(kOps) &&
        std::find(extension_ops_.begin(), extension_ops_.end(), op) == extension_ops_.end()) {
      return reply_in_order(conn, error_reply(id, "unknown_op", "unknown op '" + op + "'"));
    }
    enqueue({Request::Kind::kLine, conn, std::move(parsed.body)});
  };
  cb.on_line_too_long = [this](uint64_t conn) {
    reply_in_order(conn, error_reply(nullptr, "line_too_long", "request lines are limited to " +
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
  limits.overload_line = dump(error_reply(nullptr, "overloaded",
                                          "the server's connection or reply-queue limit was reached; this "
                                          "connection is closed (read replies as they come, or connect later)"));
  server_ = std::make_unique<LineServer>(config_.bind_address, config_.port, limits, cb);
}

ApiServer::~ApiServer() { shutdown(); }

void ApiServer::start() { server_->start(); }

void ApiServer::add_extension(ApiExtension* extension) {
  extensions_.push_back(extension);
  for (std::string& op : extension->ops()) extension_ops_.push_back(std::move(op));
}

void ApiServer::set_frame_service(render::FrameService* service) {
  frame_service_ = service;
  if (service == nullptr) return;
  frames_ = std::make_unique<FrameStream>(*service, *server_, [this](uint64_t conn) {
    auto it = clients_.find(conn);
    return it != clients_.end() && it->second.lockstep;
  });
  service->add_consumer(frames_.get());
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

void ApiServer::reply_error(uint64_t conn, const Json& id, const std::string& code,
                            const std::string& message) {
  send(conn, error_reply(id, code, message));
}

void ApiServer::reply_in_order(uint64_t conn, Json reply) {
  enqueue({Request::Kind::kReply, conn, std::move(reply)});
}

// ---------------------------------------------------------------------------------------------------
// the gate: requests, events, lockstep and pause, all on the loop thread before a control step

void ApiServer::on_gate() {
  for (;;) {
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
    if (stop_check_ && stop_check_()) return;
    for (ApiExtension* e : extensions_) e->on_gate([this](uint64_t conn, const Json& m) { send(conn, m); });
    announce_ticks();
    complete_ticks();

    bool waiting_seq = false;
    Clock::time_point next_deadline = Clock::now() + kIdleWait;
    if (lockstep_blocked()) {
      // drop clients that let their tick time out (wall clock), then wait for the others
      const Clock::time_point now = Clock::now();
      for (auto& [conn, c] : clients_) {
        if (!c.awaiting) continue;
        if (now >= c.deadline) {
          drop_lockstep(conn, c, "timeout");
          continue;
        }
        next_deadline = std::min(next_deadline, c.deadline);
        waiting_seq = waiting_seq || c.done_received;
      }
      if (!lockstep_blocked()) continue;
    } else if (!paused_) {
      return;
    } else if (steps_remaining_ > 0) {
      --steps_remaining_;
      return;
    } else if (step_reply_) {
      send(step_reply_->first, Json{{"id", step_reply_->second}, {"ok", true},
                                    {"result", {{"time_s", sim_.time_s()}, {"paused", true}}}});
      step_reply_.reset();
    }
    // wait for a request (or a lockstep deadline, or the next MAVLink seq poll)
    std::unique_lock<std::mutex> lock(mutex_);
    if (queue_.empty() && !shutdown_) {
      wake_.wait_until(lock, waiting_seq ? std::min(next_deadline, Clock::now() + kSeqPoll) : next_deadline);
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
      case Request::Kind::kConnect:
        clients_[r.conn] = Client{};
        break;
      case Request::Kind::kDisconnect:
        if (step_reply_ && step_reply_->first == r.conn) step_reply_.reset();
        if (auto it = clients_.find(r.conn); it != clients_.end()) lockstep_left(r.conn, it->second);
        for (ApiExtension* e : extensions_) e->on_disconnect(r.conn);
        if (frames_) frames_->on_disconnect(r.conn);
        clients_.erase(r.conn);
        // every request of the connection has been answered: the socket may go once that is written
        server_->close_when_sent(r.conn);
        break;
      case Request::Kind::kLine:
        handle(r.conn, r.body);
        break;
      case Request::Kind::kReply:
        send(r.conn, r.body);
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
    for (auto& [conn, c] : clients_) {
      if (c.events) send(conn, e);
    }
  }
  events_forwarded_ = log.next_seq();
}

bool ApiServer::lockstep_blocked() const {
  for (const auto& [conn, c] : clients_) {
    if (c.awaiting) return true;
  }
  return false;
}

void ApiServer::announce_ticks() {
  const double now = sim_.time_s();
  const double eps = 0.25 * sim_.physics_dt_s();
  bool mavlink_flushed = false;
  for (auto& [conn, c] : clients_) {
    if (!c.lockstep || c.awaiting || now + eps < c.next_due_s) continue;
    // the MAVLink bytes of the control steps before this tick reach the client before the tick
    if (!mavlink_flushed && seq_waiter_ != nullptr) seq_waiter_->flush_sent();
    mavlink_flushed = true;
    c.awaiting = true;
    c.done_received = false;
    c.wait_seq.clear();
    c.busy_until_s.reset();
    c.tick = std::llround(now / c.period_s);
    c.tick_time_s = now;
    // the frames due at this tick reach the client before the tick (docs/protocol.md)
    if (frames_ && frames_->has_subscriptions(conn)) frame_service_->wait_delivered();
    c.deadline = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                    std::chrono::duration<double>(c.timeout_s));
    send(conn, Json{{"event", "tick"}, {"tick", c.tick}, {"time", now}});
  }
}

void ApiServer::complete_ticks() {
  for (auto& [conn, c] : clients_) {
    if (!c.awaiting || !c.done_received) continue;
    // the MAVLink messages the client sent before "done" must have been handled
    bool seq_ok = true;
    if (seq_waiter_ != nullptr) {
      for (const auto& [vehicle, seq] : c.wait_seq) seq_ok = seq_ok && seq_waiter_->seq_processed(vehicle, seq);
    }
    if (!seq_ok) continue;
    c.awaiting = false;
    c.next_due_s = c.tick_time_s + c.period_s;
    if (c.busy_until_s && *c.busy_until_s > c.next_due_s) {
      // detached timing: the next tick for this client is the first one at or after busy_until
      c.next_due_s = std::ceil(*c.busy_until_s / c.period_s - 1e-9) * c.period_s;
    }
  }
}

void ApiServer::lockstep_left(uint64_t conn, const Client& c) {
  if (!c.lockstep || !pause_when_lockstep_empty_) return;
  for (const auto& [k, other] : clients_) {
    if (k != conn && other.lockstep) return;
  }
  // the clock cannot pass the client's next tick without it, so the pause falls at that tick
  // whenever its leaving is noticed (a done already sent counts as the tick completed): the same
  // sim time in every run
  double at_s = std::max(sim_.time_s(), c.next_due_s);
  if (c.awaiting) at_s = c.done_received ? c.tick_time_s + c.period_s : c.tick_time_s;
  pause_at_s_.insert(at_s);
  pause_when_lockstep_empty_ = false;
}

void ApiServer::drop_lockstep(uint64_t conn, Client& c, const std::string& reason) {
  lockstep_left(conn, c);
  c.lockstep = false;
  c.awaiting = false;
  send(conn, Json{{"event", "lockstep_dropped"}, {"reason", reason}, {"time", sim_.time_s()}});
}

// ---------------------------------------------------------------------------------------------------
// requests

std::optional<size_t> ApiServer::vehicle_arg(const Json& request, Error* error) const {
  auto it = request.find("vehicle");
  if (it == request.end()) {
    *error = {"missing_field", "\"vehicle\" (index or name) is required"};
    return std::nullopt;
  }
  if (it->is_number_integer() || it->is_number_unsigned()) {
    const int64_t i = it->get<int64_t>();
    if (i >= 0 && static_cast<size_t>(i) < sim_.vehicle_count()) return static_cast<size_t>(i);
  } else if (it->is_string()) {
    for (size_t i = 0; i < sim_.vehicle_count(); ++i) {
      if (sim_.vehicle_name(i) == it->get<std::string>()) return i;
    }
  } else {
    *error = {"bad_field", "\"vehicle\" must be an index or a name"};
    return std::nullopt;
  }
  *error = {"unknown_vehicle", "no vehicle " + it->dump() + " (" + std::to_string(sim_.vehicle_count()) +
                                   " vehicles)"};
  return std::nullopt;
}

Json ApiServer::vehicle_json(size_t i) const {
  const fc::TruthState t = const_cast<sim::Simulation&>(sim_).truth(i);
  const sim::VehicleRuntime& rt = sim_.runtime(i);
  Json failed = Json::array();
  for (size_t k = 0; k < rt.motors.failed.size(); ++k) {
    if (rt.motors.failed[k]) failed.push_back(k);
  }
  return Json{{"index", i},
              {"name", sim_.vehicle_name(i)},
              {"frame", sim_.airframe(i).frame},
              {"position_enu_m", vec3(t.position_enu_m)},
              {"velocity_enu_m_s", vec3(t.velocity_enu_m_s)},
              {"q_enu_body", {t.q_enu_body.w(), t.q_enu_body.x(), t.q_enu_body.y(), t.q_enu_body.z()}},
              {"rate_body_rad_s", vec3(t.rate_body_rad_s)},
              {"armed", sim_.fc(i).armed()},
              {"mode", fc::mode_name(sim_.fc(i).mode())},
              {"crashed", rt.crashed},
              {"on_ground", rt.on_ground},
              {"battery_v", rt.battery.voltage_v},
              {"battery_used_mah", rt.battery.consumed_mah},
              {"failed_motors", failed}};
}

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
  Client& client = clients_[conn];
  Error error;
  Json result = Json::object();
  auto fail = [&](const std::string& code, const std::string& message) { error = {code, message}; };

  // an extension's op (radio_ops.hpp, ...)
  for (ApiExtension* e : extensions_) {
    const std::vector<std::string> ops = e->ops();
    if (std::find(ops.begin(), ops.end(), op) == ops.end()) continue;
    if (!e->handle(conn, op, request, &result, &error.code, &error.message)) {
      return reply_error(conn, id, error.code, error.message);
    }
    return send(conn, Json{{"id", id}, {"ok", true}, {"result", result}});
  }

  if (const auto bad = mistyped_field(request, kBuiltinFields)) return reply_error(conn, id, "bad_field", *bad);

  if (op == "status") {
    int lockstep = 0;
    for (const auto& [k, c] : clients_) lockstep += c.lockstep ? 1 : 0;
    result = {{"protocol", kProtocolVersion},
              {"time_s", sim_.time_s()},
              {"steps", sim_.step_count()},
              {"paused", paused_},
              {"rate", runner_ ? Json(runner_->rate()) : Json(nullptr)},
              {"physics_hz", 1.0 / sim_.physics_dt_s()},
              {"control_hz", 1.0 / sim_.control_dt_s()},
              {"seed", sim_.config().seed},
              {"vehicles", sim_.vehicle_count()},
              {"lockstep_clients", lockstep},
              {"events", sim_.events().next_seq()},
              {"realism", sim::realism_name(sim_.config().field.realism)}};
  } else if (op == "pause") {
    paused_ = true;
    result = {{"time_s", sim_.time_s()}, {"paused", true}};
  } else if (op == "pause_at") {
    // arm a pause at a sim time and/or when the last lockstep client leaves (deterministic ends)
    const auto at = number_field(request, "time_s");
    const bool empty = request.value("lockstep_empty", false);
    if (!at && !empty) {
      fail("missing_field", "\"time_s\" or \"lockstep_empty\": true is required");
    } else if (at && !std::isfinite(*at)) {
      fail("bad_field", "\"time_s\" must be a finite sim time");
    } else {
      if (at) pause_at_s_.insert(*at);
      if (empty) pause_when_lockstep_empty_ = true;
      result = {{"time_s", sim_.time_s()},
                {"pause_at_s", Json(std::vector<double>(pause_at_s_.begin(), pause_at_s_.end()))},
                {"lockstep_empty", pause_when_lockstep_empty_}};
    }
  } else if (op == "resume") {
    paused_ = false;
    steps_remaining_ = 0;
    result = {{"time_s", sim_.time_s()}, {"paused", false}};
  } else if (op == "step") {
    // N control steps (default 1) or a duration rounded to whole control steps; pauses first
    const auto steps = number_field(request, "steps");
    const auto duration = number_field(request, "duration_s");
    double n = 1;
    if (steps) n = *steps;
    if (duration) n = std::round(*duration / control_dt_s());
    if (!(n >= 1 && n <= 1e9) || std::floor(n) != n) {
      fail("bad_field", "\"steps\" must be an integer in [1, 1e9] (or \"duration_s\" at least one control step)");
    } else if (step_reply_) {
      fail("busy", "another step request is in progress");
    } else {
      paused_ = true;
      steps_remaining_ = static_cast<uint64_t>(n);
      step_reply_ = std::make_pair(conn, id);
      return;  // answered when the steps are done
    }
  } else if (op == "set_rate") {
    const auto rate = number_field(request, "rate");
    if (!rate) {
      fail("missing_field", "\"rate\" (a number: 1 = real time, 0 = as fast as possible) is required");
    } else if (*rate != 0.0 && !sim::finite_in(*rate, kMinRate, kMaxRate)) {
      fail("bad_field", "\"rate\" must be 0 (as fast as possible) or in [0.001, 1e6]");
    } else if (runner_ == nullptr) {
      fail("not_available", "this server has no clock runner");
    } else {
      runner_->set_rate(*rate);
      result = {{"rate", *rate}};
    }
  } else if (op == "reset") {
    // an integer seed travels exactly; a number in double form must be a whole one below 2^64
    const auto it = request.find("seed");
    std::optional<uint64_t> seed;
    if (it != request.end()) {
      seed = it->is_number_unsigned() ? std::optional<uint64_t>(it->get<uint64_t>())
                                      : sim::checked_integer<uint64_t>(it->get<double>());
    }
    if (it != request.end() && !seed) {
      fail("bad_field", "\"seed\" must be an integer in [0, 2^64)");
    } else {
      const uint64_t s = seed.value_or(sim_.config().seed);
      sim_.reset(s);
      events_forwarded_ = 0;
      pause_at_s_.clear();
      pause_when_lockstep_empty_ = false;
      if (frames_) frames_->clear_blackouts();  // their times were on the old clock
      for (auto& [k, c] : clients_) {
        c.awaiting = false;
        c.next_due_s = 0.0;
        if (c.events) send(k, Json{{"event", "reset"}, {"seed", s}});
      }
      result = {{"seed", s}, {"time_s", sim_.time_s()}};
    }
  } else if (op == "vehicles") {
    result = Json::array();
    for (size_t i = 0; i < sim_.vehicle_count(); ++i) result.push_back(vehicle_json(i));
    result = {{"time_s", sim_.time_s()}, {"vehicles", result}};
  } else if (op == "truck") {
    if (objects_.trucks.empty()) {
      fail("not_available", "this world has no truck");
    } else {
      Json trucks = Json::array();
      for (const objects::Truck* truck : objects_.trucks) {
        const objects::TruckState s = truck->state(sim_.time_s());
        trucks.push_back({{"name", s.name},
                          {"position_enu_m", vec3(s.position_enu_m)},
                          {"velocity_enu_m_s", vec3(s.velocity_enu_m_s)},
                          {"yaw_rad", s.yaw_rad},
                          {"speed_m_s", s.speed_m_s},
                          {"s_m", s.s_m},
                          {"laps", s.laps},
                          {"track_length_m", truck->track().length_m()},
                          {"deck_centre_enu_m", vec3(s.deck_centre_enu_m)},
                          {"carried_vehicles", s.carried_vehicles}});
      }
      result = {{"time_s", sim_.time_s()}, {"trucks", trucks}};
    }
  } else if (op == "balloons") {
    if (objects_.balloons == nullptr) {
      fail("not_available", "this world has no balloons");
    } else {
      Json balloons = Json::array();
      for (const objects::BalloonState& b : objects_.balloons->balloons()) {
        balloons.push_back({{"name", b.name},
                            {"position_enu_m", vec3(b.position_enu_m)},
                            {"radius_m", b.radius_m},
                            {"popped", b.popped},
                            {"popped_by", b.popped ? Json(b.popped_by) : Json(nullptr)},
                            {"popped_time_s", b.popped ? Json(b.popped_time_s) : Json(nullptr)}});
      }
      result = {{"time_s", sim_.time_s()}, {"balloons", balloons}};
    }
  } else if (op == "events" || op == "subscribe_events") {
    const auto from_number = number_field(request, "from_seq");
    const auto from = from_number ? sim::checked_integer<uint64_t>(*from_number) : std::optional<uint64_t>(0);
    if (!from) {
      fail("bad_field", "\"from_seq\" must be a non-negative integer");
    } else {
      // the events already forwarded (later ones stream to subscribers), from from_seq or the oldest
      // still held: first_seq > from_seq tells the client that the ones between were dropped
      const uint64_t from_seq = *from;
      const sim::EventLog& log = sim_.events();
      Json list = Json::array();
      for (const sim::Event& e : log.recent()) {
        if (e.seq >= from_seq && e.seq < events_forwarded_) list.push_back(event_json(e));
      }
      const uint64_t first_seq = std::min<uint64_t>(log.first_seq(), events_forwarded_);
      // a subscriber gets the backlog in the reply; later events stream as {"event": "sim_event", ...}
      if (op == "subscribe_events") client.events = true;
      result = {{"events", list}, {"first_seq", first_seq}, {"next_seq", events_forwarded_}};
    }
  } else if (op == "unsubscribe_events") {
    client.events = false;
  } else if (op == "kill_vehicle" || op == "motor_failure" || op == "gps_glitch" || op == "gps_denied" ||
             op == "link_drop") {
    const auto v = vehicle_arg(request, &error);
    if (v) {
      if (op == "kill_vehicle") {
        const std::string reason = string_field(request, "reason").value_or("fault injection");
        sim_.record(sim::EventType::kVehicleKilled, static_cast<int>(*v), reason);
        sim_.kill_vehicle(*v, "killed: " + reason);
      } else if (op == "motor_failure") {
        const auto rotor = number_field(request, "rotor");
        const size_t rotors = sim_.airframe(*v).rotors.size();
        if (!rotor) {
          fail("missing_field", "\"rotor\" (index) is required");
        } else if (*rotor < 0 || *rotor >= static_cast<double>(rotors) || std::floor(*rotor) != *rotor) {
          fail("bad_field", "\"rotor\" must be in [0, " + std::to_string(rotors) + ")");
        } else {
          sim_.set_motor_failed(*v, static_cast<size_t>(*rotor), bool_field(request, "failed").value_or(true));
        }
      } else if (op == "gps_glitch") {
        auto it = request.find("offset_enu_m");
        if (it == request.end()) {
          fail("missing_field", "\"offset_enu_m\" [x, y, z] is required ([0, 0, 0] clears the glitch)");
        } else if (it->size() != 3 || !(*it)[0].is_number() || !(*it)[1].is_number() || !(*it)[2].is_number() ||
                   std::abs((*it)[0].get<double>()) > kMaxGlitch_m || std::abs((*it)[1].get<double>()) > kMaxGlitch_m ||
                   std::abs((*it)[2].get<double>()) > kMaxGlitch_m) {
          fail("bad_field", "\"offset_enu_m\" must be three numbers of at most 1e5 m");
        } else {
          sim_.fc(*v).set_gps_glitch(
              Eigen::Vector3d((*it)[0].get<double>(), (*it)[1].get<double>(), (*it)[2].get<double>()));
        }
      } else if (op == "gps_denied") {
        sim_.fc(*v).set_gps_denied(bool_field(request, "denied").value_or(true));
      } else if (op == "link_drop") {
        if (link_ == nullptr) {
          fail("not_available", "no MAVLink endpoint is attached to this server");
        } else if (!link_->set_link_down(*v, bool_field(request, "down").value_or(true))) {
          fail("not_available", "vehicle " + std::to_string(*v) + " has no MAVLink link");
        }
      }
      if (error.code.empty()) result = {{"vehicle", *v}, {"time_s", sim_.time_s()}};
    }
  } else if (op == "gimbal") {
    const auto name = string_field(request, "gimbal");
    objects::Gimbal* g = nullptr;
    if (objects_.gimbals != nullptr && name) {
      for (objects::Gimbal& x : objects_.gimbals->gimbals()) {
        if (x.name == *name) g = &x;
      }
    }
    const auto mode = string_field(request, "mode");
    const auto pitch_deg = number_field(request, "pitch_deg");
    const auto yaw_deg = number_field(request, "yaw_deg");
    const auto angle_ok = [](const std::optional<double>& a) {
      return !a || sim::finite_in(*a, -kMaxGimbalAngle_deg, kMaxGimbalAngle_deg);
    };
    if (!name) {
      fail("missing_field", "\"gimbal\" (the gimbal body's name) is required");
    } else if (g == nullptr) {
      fail("bad_field", "no gimbal named '" + *name + "'");
    } else if (mode && *mode != "down" && *mode != "forward" && *mode != "targets") {
      fail("bad_field", "\"mode\" must be down, forward or targets");
    } else if (!angle_ok(pitch_deg) || !angle_ok(yaw_deg)) {
      fail("bad_field", "\"pitch_deg\" and \"yaw_deg\" must be in [-360, 360]");
    } else {
      if (mode) {
        g->mode = *mode == "down"      ? objects::GimbalMode::kDown
                  : *mode == "forward" ? objects::GimbalMode::kForward
                                       : objects::GimbalMode::kTargets;
      }
      if (pitch_deg) g->pitch_rad = *pitch_deg * M_PI / 180.0;
      if (yaw_deg) g->yaw_rad = *yaw_deg * M_PI / 180.0;
      result = {{"gimbal", g->name}, {"mode", objects::gimbal_mode_name(g->mode)},
                {"pitch_deg", g->pitch_rad * 180.0 / M_PI}, {"yaw_deg", g->yaw_rad * 180.0 / M_PI}};
    }
  } else if (op == "wind") {
    // set what is given (speed, direction, turbulence), start a gust if asked; answer the wind now
    airframe::WindParams w = sim_.wind().params();
    const auto speed = number_field(request, "speed_m_s");
    const auto from = number_field(request, "from_deg");
    const auto turbulence = number_field(request, "turbulence_sd_m_s");
    const auto gust = number_field(request, "gust_m_s");
    const auto gust_duration = number_field(request, "gust_duration_s");
    if (speed) w.speed_m_s = *speed;
    if (from) w.from_deg = *from;
    if (turbulence) w.turbulence_sd_m_s = *turbulence;
    const std::string why = airframe::validate(w);
    if (!why.empty() || (from && std::abs(*from) > 360.0)) {
      fail("bad_field", why.empty() ? "\"from_deg\" must be in [-360, 360]" : why);
    } else if ((gust && !sim::finite_in(*gust, 0.0, 50.0)) ||
               (gust_duration && !sim::finite_in(*gust_duration, 0.01, 600.0))) {
      fail("bad_field", "\"gust_m_s\" must be in [0, 50] and \"gust_duration_s\" in [0.01, 600]");
    } else {
      if (speed || from || turbulence) sim_.wind().set_params(w);
      if (gust) sim_.wind().gust(*gust, gust_duration.value_or(w.gust_duration_s));
      const airframe::WindField& f = sim_.wind();
      result = {{"speed_m_s", f.params().speed_m_s},
                {"from_deg", f.params().from_deg},
                {"turbulence_sd_m_s", f.params().turbulence_sd_m_s},
                {"length_scale_m", f.params().length_scale_m},
                {"gust_m_s", f.gust_m_s()},
                {"velocity_enu_m_s", vec3(f.velocity_enu_m_s())},
                {"realism", sim::realism_name(sim_.config().field.realism)},
                {"time_s", sim_.time_s()}};
    }
  } else if (op == "lockstep_join") {
    const auto period = number_field(request, "period_s");
    const auto timeout = number_field(request, "timeout_s");
    if (!period) {
      fail("missing_field", "\"period_s\" (sim seconds between ticks) is required");
    } else if (!(*period > 0.0) || !std::isfinite(*period) || *period > 3600.0) {
      fail("bad_field", "\"period_s\" must be in (0, 3600]");
    } else if (timeout && !(*timeout > 0.0 && *timeout <= kMaxLockstepTimeout_s)) {
      // the deadline is a steady_clock time point: 1e10 s would overflow it and count as expired
      fail("bad_field", "\"timeout_s\" must be in (0, 1e6]");
    } else {
      // whole control steps, at least one; the first tick is the next multiple of the period
      client.period_steps = std::max<int64_t>(1, std::llround(*period / control_dt_s()));
      client.period_s = client.period_steps * control_dt_s();
      client.lockstep = true;
      client.awaiting = false;
      client.timeout_s = timeout.value_or(config_.lockstep_timeout_s);
      client.next_due_s = std::ceil(sim_.time_s() / client.period_s - 1e-9) * client.period_s;
      result = {{"period_s", client.period_s}, {"first_tick_time", client.next_due_s},
                {"timeout_s", client.timeout_s}};
    }
  } else if (op == "lockstep_leave") {
    lockstep_left(conn, client);
    client.lockstep = false;
    client.awaiting = false;
  } else if (op == "done") {
    const auto tick = number_field(request, "tick");
    const auto busy = number_field(request, "busy_until");
    auto seqs = request.find("mavlink_seq");
    if (!client.lockstep) {
      fail("not_joined", "\"done\" without lockstep_join");
    } else if (!client.awaiting || client.done_received) {
      fail("bad_state", "no tick is waiting for \"done\"");
    } else if (has_field(request, "tick") && (!tick || *tick != static_cast<double>(client.tick))) {
      fail("bad_field", "the tick waiting is " + std::to_string(client.tick));
    } else if (has_field(request, "busy_until") && (!busy || !std::isfinite(*busy))) {
      fail("bad_field", "\"busy_until\" must be a sim time in seconds");
    } else if (seqs != request.end() && !seqs->is_object()) {
      fail("bad_field", "\"mavlink_seq\" must be an object {vehicle: seq}");
    } else {
      std::map<size_t, uint8_t> wait;
      if (seqs != request.end()) {
        for (auto it = seqs->begin(); it != seqs->end() && error.code.empty(); ++it) {
          Json probe = {{"vehicle", it.key()}};
          // "0" names vehicle 0; any other string a vehicle name
          char* end = nullptr;
          const long index = std::strtol(it.key().c_str(), &end, 10);
          if (!it.key().empty() && *end == '\0') probe["vehicle"] = index;
          const auto v = vehicle_arg(probe, &error);
          if (v && (!it.value().is_number_integer() || it.value().get<int64_t>() < 0 ||
                    it.value().get<int64_t>() > 255)) {
            fail("bad_field", "MAVLink sequence numbers are integers in [0, 255]");
          } else if (v) {
            wait[*v] = static_cast<uint8_t>(it.value().get<int64_t>());
          }
        }
      }
      if (error.code.empty()) {
        client.done_received = true;
        client.wait_seq = wait;
        if (busy) client.busy_until_s = *busy;
        result = {{"tick", client.tick},
                  {"mavlink_seq_checked", seq_waiter_ != nullptr}};
      }
    }
  } else if (op == "camera_list" || op == "camera_subscribe" || op == "camera_unsubscribe") {
    if (!frames_) {
      fail("not_available", "this server renders no camera frames");
    } else if (!frames_->handle(conn, op, request, &result, &error.code, &error.message)) {
      // error set
    }
  } else if (op == "camera_blackout") {
    if (!frames_) {
      fail("not_available", "this server renders no camera frames");
    } else if (!frames_->blackout(request, sim_.time_s(), &result, &error.code, &error.message)) {
      // error set
    }
  }

  if (!error.code.empty()) return reply_error(conn, id, error.code, error.message);
  send(conn, Json{{"id", id}, {"ok", true}, {"result", result}});
}

}  // namespace uavsim::server::api
