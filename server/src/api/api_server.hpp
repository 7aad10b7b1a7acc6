// The sim socket API (docs/protocol.md): one TCP port, newline-delimited JSON, protocol version 1.
// Control (status, pause, resume, step, set_rate, reset), ground-truth queries (vehicles, truck,
// balloons), the event stream, fault injection, gimbal pointing and the lockstep contract
// (seed 5.3/6.5: gzuav's Begin-Tick/End-Tick).
//
// Ops: every op is an entry of one OpTable (op_table.hpp), registered by its group: ClockOps,
// EventOps and LockstepOps (the clock, the event stream and the lockstep contract), VehicleOps
// (ground truth, faults, gimbals, wind), FrameStream (camera frames) and the groups added with
// add_group (radio, sensors, overlay). The hello's op list, the unknown_op check and the dispatch
// all read that table; this server is the transport, the dispatch and the gate. The one op it
// answers itself is auth, which belongs to the transport.
//
// Threads: socket I/O runs on the LineServer's I/O thread (shared with the MAVLink endpoints in
// uavsim-server); every request that touches the simulation is
// queued and executed on the loop thread inside the control gate (gate(), registered with
// Runner::add_gate in the step schedule's queued-tasks phase), before the control step, in arrival
// order. The gate is also where pause, single-stepping and lockstep hold the clock, so the loop
// thread keeps serving requests while held.
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <span>
#include <string>
#include <vector>

#include "api/clock_ops.hpp"
#include "api/event_ops.hpp"
#include "api/frame_stream.hpp"
#include "api/line_server.hpp"
#include "api/lockstep_coordinator.hpp"
#include "api/lockstep_ops.hpp"
#include "api/op_table.hpp"
#include "api/shm_transport.hpp"
#include "api/vehicle_ops.hpp"
#include "objects/world_objects.hpp"
#include "sim/runner.hpp"
#include "sim/simulation.hpp"

namespace uavsim::server::api {

// Implemented by the MAVLink endpoint: has the message with this sequence number, sent by a client
// on a vehicle's link, been handled (its commands posted to the simulation)? The lockstep contract
// waits for it before a tick ends, so commands sent before "done" take effect at that tick.
class SeqWaiter {
 public:
  virtual ~SeqWaiter() = default;
  // True once the endpoint has processed the MAVLink message with sequence seq (0-255, as in the
  // MAVLink header) on vehicle's link, or any later one. Thread-safe.
  virtual bool seq_processed(size_t vehicle, uint8_t seq) const = 0;
  // Registers the server's "a seq may have been processed" call, which the endpoint makes (any
  // thread) after handling messages, so a gate waiting for a done's mavlink_seq wakes at once. The
  // default registers nothing: the gate then polls every millisecond.
  virtual void set_progress_listener(std::function<void()> listener) { (void)listener; }
  // Returns once every MAVLink byte the endpoint has queued for its clients so far (the telemetry
  // and replies of the control steps before now) has been written to their sockets. Called before a
  // tick is announced, so a lockstep client has its vehicles' telemetry stamped before the tick
  // when the tick arrives. The default does nothing (an endpoint that writes synchronously). Loop
  // thread only.
  virtual void flush_sent() {}
};

struct ApiConfig {
  std::string bind_address = "127.0.0.1";
  uint16_t port = 5700;  // 0: an ephemeral port (tests)
  double lockstep_timeout_s =
      10.0;  // wall time a lockstep client may take for a tick before it is dropped
  size_t max_line_bytes = 1u << 20;  // longer request lines get an error reply and are skipped
  size_t max_connections = 64;       // one more is sent an "overloaded" error and closed
  // unsent replies, events and frames per connection / for all together: a connection that would
  // pass either is sent an "overloaded" error and closed (docs/protocol.md)
  size_t max_pending_bytes = 64u << 20;
  size_t max_total_pending_bytes = 256u << 20;
  bool start_paused = false;  // hold the clock at start until a client sends resume or step
  // A shared secret: a connection must send it ({"op":"auth","token":...}, or a "token" field in
  // its first request) before any other op is served. Unset: no authentication.
  std::optional<std::string> token;
  // Serve the shared-memory stream (op lockstep_shm) to clients connecting from loopback.
  bool shm = true;
  // The server's network I/O loop, shared with the MAVLink endpoints (it must outlive this server;
  // its owner starts it). Null: the API's socket I/O runs on a loop of its own.
  net::EventLoop* io_loop = nullptr;
};

class ApiServer {
 public:
  // runner may be null (set_rate then answers not_available). Binds the port: throws
  // std::runtime_error naming the address if that fails (a startup error). Construct before the
  // loop starts.
  ApiServer(sim::Simulation& sim, sim::Runner* runner, objects::ObjectSet objects,
            const ApiConfig& config);
  ~ApiServer();
  ApiServer(const ApiServer&) = delete;
  ApiServer& operator=(const ApiServer&) = delete;

  // Optional endpoint hooks. Before start().
  void set_link_control(LinkControl* link) { vehicle_ops_.set_link_control(link); }
  void set_seq_waiter(SeqWaiter* waiter);
  // Camera frames (the FrameStream group's camera_* ops); without one they answer not_available.
  // The service's capture() runs in the runner's gate before this server's gate. Before start().
  void set_frame_service(render::FrameService* service);
  // Serves a group's ops (registers them in the op table) and calls its hooks; it must outlive this
  // server. Throws std::logic_error if it registers an op name already served. Before start().
  void add_group(OpGroup* group);
  // The address a connection came from (for op groups whose policy depends on it, e.g. RadioOps'
  // GcsTargetPolicy); empty once it has closed. Thread-safe.
  std::string peer_address(uint64_t conn) const;
  // Every op served, in registration order (the hello's "ops"). After start(). Thread-safe.
  std::vector<std::string> op_names() const { return ops_.names(); }
  // Polled while the gate holds the clock (pause, lockstep); true releases it (e.g. SIGINT). Before
  // start().
  void set_stop_check(std::function<bool()> check) { stop_check_ = std::move(check); }

  // Starts serving connections (the I/O thread). Call once, before or after the loop starts.
  void start();
  // Releases a held gate for good and stops the I/O thread. Thread-safe; idempotent.
  void shutdown();
  uint16_t port() const { return server_->port(); }
  // Connections open now. Thread-safe.
  size_t connection_count() const { return connections_.load(); }
  // The connections' shared-memory streams (op lockstep_shm): RadioOps hands it the radio frames of
  // a tick record. Valid for the server's life.
  ShmTransport& shm_transport() { return *shm_; }

  // The control gate for Runner::add_gate (queued-tasks phase): runs queued requests and holds the
  // clock while paused or while a lockstep client has not finished its tick. Loop thread only.
  sim::Runner::Gate gate() {
    return [this](double) { on_gate(); };
  }

 private:
  using Json = nlohmann::json;
  using Clock = std::chrono::steady_clock;

  struct Request {
    // kReply: an answer made on the I/O thread (a malformed line), sent from the loop in its turn
    enum class Kind { kLine, kDisconnect, kReply } kind = Kind::kLine;
    uint64_t conn = 0;
    Json body;                 // the request, or the reply for kReply
    bool errors_only = false;  // a binary request from a request ring: answered only if refused
  };

  // I/O thread side
  // Stages a request (or an in-order reply) for the loop; flush_staged() queues what one read of a
  // connection brought at once, so the gate serves a client's burst (requests and its done) in one
  // pass.
  void enqueue(Request request);
  void flush_staged();
  void send(uint64_t conn, const Json& message);
  // a binary radio_send or done from a connection's request ring (common/shm_requests.hpp), queued
  // as its JSON form
  void on_binary_request(uint64_t conn, uint16_t type, std::span<const uint8_t> payload);
  void reply_error(uint64_t conn, const Json& id, ApiError code, const std::string& message);
  // queues a reply behind the connection's earlier requests (the loop sends it in order)
  void reply_in_order(uint64_t conn, Json reply);
  // Sends a reply to conn, or holds it behind conn's step in progress (replies keep request order).
  void reply(uint64_t conn, const Json& message);

  // loop thread side
  void on_gate();
  // request (a query) served for conn now, outside the request queue: {"result": ...} or
  // {"error": {"code", "message"}} (lockstep_join's with_tick, before each of conn's ticks)
  Json serve_query(uint64_t conn, const Json& request);
  void drain();
  void handle(uint64_t conn, const Json& request, bool errors_only);
  // spec's handler run on request for conn, once its typed fields are checked (a mistyped one
  // fails the reply with bad_field unseen by the handler); the watchdog names the op meanwhile.
  // What handle() and serve_query() both do.
  OpReply run_op(uint64_t conn, const OpSpec& spec, const Json& request);
  // sends the lockstep ticks due now, each after what is due before it (MAVLink, frames)
  void announce_ticks();

  sim::Simulation& sim_;
  sim::Runner* runner_;
  ApiConfig config_;
  SeqWaiter* seq_waiter_ = nullptr;
  LockstepCoordinator::SeqProcessed seq_processed_;  // seq_waiter_'s, or null without one
  std::function<bool()> stop_check_;
  std::unique_ptr<LineServer> server_;
  std::unique_ptr<ShmTransport> shm_;  // after server_: its rings are written through it
  // every op, registered before start() and read-only afterwards (the I/O thread looks names up)
  OpTable ops_;
  std::vector<OpGroup*> groups_;  // their hooks; set before start()
  // what the groups' hooks are given: send on this server, and whether a connection is in lockstep
  const OpGroup::Send send_fn_ = [this](uint64_t conn, const Json& m) { send(conn, m); };
  const OpGroup::InLockstep in_lockstep_fn_ = [this](uint64_t conn) {
    return lockstep_.joined(conn);
  };
  // loop thread only
  sim::SteadyWallClock wall_clock_;  // lockstep deadlines
  LockstepCoordinator lockstep_;     // which connections gate the clock, their ticks
  // the server's own op groups (built once the transport is): the clock, events, lockstep
  std::unique_ptr<ClockOps> clock_ops_;
  std::unique_ptr<EventOps> event_ops_;
  std::unique_ptr<LockstepOps> lockstep_ops_;
  VehicleOps vehicle_ops_;
  std::unique_ptr<FrameStream> frames_;

  std::mutex mutex_;  // guards queue_ and shutdown_
  std::condition_variable wake_;
  // counts the SeqWaiter's progress calls (guarded by mutex_): the gate waits for it to change
  uint64_t seq_progress_ = 0;
  std::deque<Request> queue_;
  std::vector<Request> staged_;  // I/O thread only: enqueue()'d, not flushed yet
  bool shutdown_ = false;
  std::atomic<size_t> connections_{0};
  std::set<uint64_t> authenticated_;  // connections that sent the token; I/O thread only
};

}  // namespace uavsim::server::api
