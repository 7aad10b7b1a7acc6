#include "api/lockstep_ops.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "api/request_fields.hpp"
#include "api/vehicle_arg.hpp"
#include "sim/checked_number.hpp"
#include "uavsim/common/shm_ring.hpp"

namespace uavsim::server::api {

namespace {

// lockstep_join's timeout_s: a deadline further out is no different from none
constexpr double kMaxLockstepTimeout_s = 1e6;
// lockstep_join's period_s: an hour of sim time between ticks at most
constexpr double kMaxPeriod_s = 3600.0;
// lockstep_join's with_tick: ops that only read the world (answering them at a tick changes
// nothing a request at that tick would not), and how many a client may ask for
constexpr const char* kTickQueries[] = {"vehicles", "truck", "balloons",
                                        "status",   "wind",  "gimbal"};
constexpr size_t kMaxTickQueries = 8;

// with_tick's list, or why it is not one: an array of at most kMaxTickQueries objects, each with
// an "op" of kTickQueries (the ops' own fields are checked when they run, at each tick)
std::optional<std::vector<nlohmann::json>> tick_queries(const nlohmann::json& list,
                                                        std::string* why) {
  if (!list.is_array() || list.size() > kMaxTickQueries) {
    *why = "\"with_tick\" must be an array of at most " + std::to_string(kMaxTickQueries) +
           " requests";
    return std::nullopt;
  }
  std::vector<nlohmann::json> out;
  for (const nlohmann::json& q : list) {
    const auto op = q.is_object() ? q.find("op") : q.end();
    const bool known =
        q.is_object() && op != q.end() && op->is_string() &&
        std::any_of(std::begin(kTickQueries), std::end(kTickQueries),
                    [&](const char* name) { return op->get<std::string>() == name; });
    if (!known) {
      *why =
          "each of \"with_tick\" is a request {\"op\": ...} of vehicles, truck, balloons, "
          "status, wind or gimbal";
      return std::nullopt;
    }
    out.push_back(q);
  }
  return out;
}

}  // namespace

LockstepOps::LockstepOps(sim::Simulation& sim, LockstepCoordinator& lockstep, ClockOps& clock,
                         ShmTransport* shm, Server server)
    : sim_(sim), lockstep_(lockstep), clock_(clock), shm_(shm), server_(std::move(server)) {}

void LockstepOps::register_ops(OpTable& table) {
  const OpRegistrar<LockstepOps> add(table, this, "lockstep");
  add("lockstep_join", &LockstepOps::op_join);
  add("lockstep_leave", &LockstepOps::op_leave);
  add("done", &LockstepOps::op_done);
  add("lockstep_shm", &LockstepOps::op_shm);
}

void LockstepOps::on_reset() {
  lockstep_.reset();
  if (shm_ != nullptr) shm_->end_quiet_all();
}

void LockstepOps::on_disconnect(uint64_t conn) {
  with_tick_.erase(conn);
  clock_.lockstep_left(lockstep_.leave(conn, sim_.time_s()));
}

void LockstepOps::op_join(uint64_t conn, const Json& request, OpReply* reply) {
  const auto period = number_field(request, "period_s");
  const auto timeout = number_field(request, "timeout_s");
  if (!period) {
    return reply->fail(ApiError::kMissingField,
                       "\"period_s\" (sim seconds between ticks) is required");
  }
  if (!(*period > 0.0) || !std::isfinite(*period) || *period > kMaxPeriod_s) {
    return reply->fail(ApiError::kBadField, "\"period_s\" must be in (0, 3600]");
  }
  if (timeout && !(*timeout > 0.0 && *timeout <= kMaxLockstepTimeout_s)) {
    return reply->fail(ApiError::kBadField, "\"timeout_s\" must be in (0, 1e6]");
  }
  // the first tick is the next multiple of the period at or after now; strictly after now for a
  // connection whose output of now was prepared before it joined (a camera subscriber: the frame
  // due at a tick must have been captured for a lockstep client)
  const bool after_now = server_.prepared_before_join(conn);
  const double from_s = sim_.time_s() + (after_now ? 0.5 * sim_.control_dt_s() : 0.0);
  std::vector<Json> with_tick;
  if (has_field(request, "with_tick")) {
    std::string why;
    auto queries = tick_queries(request["with_tick"], &why);
    if (!queries) return reply->fail(ApiError::kBadField, why);
    with_tick = std::move(*queries);
  }
  const LockstepCoordinator::Joined joined = lockstep_.join(conn, *period, timeout, from_s);
  if (with_tick.empty()) {
    with_tick_.erase(conn);
  } else {
    with_tick_[conn] = std::move(with_tick);
  }
  reply->result = {{"period_s", joined.period_s},
                   {"first_tick_time", joined.first_tick_time_s},
                   {"timeout_s", joined.timeout_s},
                   {"mavlink_seq_checked", server_.seq_checked()}};
}

void LockstepOps::op_leave(uint64_t conn, const Json&, OpReply*) {
  with_tick_.erase(conn);
  clock_.lockstep_left(lockstep_.leave(conn, sim_.time_s()));
}

void LockstepOps::before_tick(uint64_t conn, const Send& send) {
  const auto it = with_tick_.find(conn);
  if (it == with_tick_.end()) return;
  Json results = Json::array();
  for (const Json& q : it->second) results.push_back(server_.serve_query(conn, q));
  send(conn,
       Json{{"event", "tick_results"}, {"time", sim_.time_s()}, {"results", std::move(results)}});
}

void LockstepOps::op_done(uint64_t conn, const Json& request, OpReply* reply) {
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
      if (!it.value().is_number_integer() || it.value().get<int64_t>() < 0 ||
          it.value().get<int64_t>() > 255) {
        return reply->fail(ApiError::kBadField,
                           "MAVLink sequence numbers are integers in [0, 255]");
      }
      wait[*v] = static_cast<uint8_t>(it.value().get<int64_t>());
    }
  }
  const int64_t done_tick = lockstep_.take_done(conn, busy, std::move(wait));
  // quiet (a client that waits for nothing but its next tick, like client_cpp's EventLoop): on a
  // ring it is not woken again before that tick, which brings this reply and what else comes
  // meanwhile; unless a step of conn is in progress (its reply, awaited, may come first). Asked
  // for, not assumed: a blocking client (SimConnection::done) waits for this reply, and the tick
  // may depend on what it does next (another of its connections' done).
  if (bool_field(request, "quiet").value_or(false) && shm_ != nullptr &&
      !clock_.step_in_progress(conn)) {
    shm_->quiet_until_tick(conn);
  }
  reply->result = {{"tick", done_tick}, {"mavlink_seq_checked", server_.seq_checked()}};
}

void LockstepOps::op_shm(uint64_t conn, const Json& request, OpReply* reply) {
  // only for a client on this machine, once, and not behind a step's reply (which must come on TCP)
  if (shm_ == nullptr) {
    return reply->fail(ApiError::kNotAvailable, "this server serves no shared-memory stream");
  }
  const std::string peer = server_.peer_address(conn);
  if (peer.rfind("127.", 0) != 0) {
    return reply->fail(ApiError::kNotAvailable,
                       "the shared-memory stream is for clients on the server's machine; "
                       "this one connects from " +
                           peer);
  }
  if (shm_->attached(conn)) {
    return reply->fail(ApiError::kBadState,
                       "this connection is on the shared-memory stream already");
  }
  if (clock_.step_in_progress(conn)) {
    return reply->fail(ApiError::kBusy, "a step request of this connection is in progress");
  }
  // a ring's size: absent, the default; otherwise a power of two the ring takes
  const auto ring_size = [&request](const char* key, size_t fallback) -> std::optional<size_t> {
    const auto bytes = number_field(request, key);
    const auto n =
        bytes ? sim::checked_integer<uint64_t>(*bytes) : std::optional<uint64_t>(fallback);
    if (!n || common::shm::region_bytes(static_cast<size_t>(*n)) == 0) return std::nullopt;
    return static_cast<size_t>(*n);
  };
  const auto ring_bytes = ring_size("ring_bytes", ShmTransport::kDefaultRingBytes);
  const auto request_bytes =
      ring_size("request_ring_bytes", ShmTransport::kDefaultRequestRingBytes);
  if (!ring_bytes || !request_bytes) {
    return reply->fail(ApiError::kBadField, std::string("\"") +
                                                (ring_bytes ? "request_ring_bytes" : "ring_bytes") +
                                                "\" must be a power of two in [65536, 268435456]");
  }
  const auto requests = bool_field(request, "requests");
  if (has_field(request, "requests") && !requests) {
    return reply->fail(ApiError::kBadField, "\"requests\" must be a boolean");
  }
  std::string why;
  const auto offer =
      shm_->offer(conn, *ring_bytes, requests.value_or(false) ? *request_bytes : 0, &why);
  if (!offer) return reply->fail(ApiError::kNotAvailable, "no shared-memory stream: " + why);
  // the reply is the last message on TCP; everything after it goes to the ring
  const Json id = request.contains("id") ? request["id"] : Json(nullptr);
  server_.send(conn, ok_reply(id, *offer));
  shm_->activate(conn);
  reply->deferred = true;
}

}  // namespace uavsim::server::api
