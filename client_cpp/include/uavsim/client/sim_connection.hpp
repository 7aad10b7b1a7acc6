// SimConnection: a blocking client of the simulator's sim API (docs/protocol.md), for launchers,
// scoring harnesses and tests. Newline-delimited JSON over TCP: requests get their reply by id;
// streamed messages (those with an "event" field: sim_event, tick, radio, frame, sensor, ...) read
// meanwhile are queued for take_messages() or handed to a handler registered with on_message().
//
// The API's ground truth is for scoring and tests; a mission decides with what a real drone has.
//
// Thread contract: a connection belongs to the thread that created it (its owner thread); no method
// is thread-safe, and debug builds assert the owner. Handlers run on that thread, inside the call
// that read their message.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "uavsim/client/result.hpp"

namespace uavsim::client {

// A message the server streamed without being asked: {"event": KIND, ...}.
struct SimMessage {
  nlohmann::json json;
  std::string payload;  // a `frame`'s image bytes (exactly its header's `bytes`); empty otherwise
  // The message's "event" field ("tick", "sim_event", "frame", ...); empty if it has none.
  // Thread-safe.
  std::string kind() const;
};

class SimConnection {
 public:
  // Largest line accepted from the server, and largest frame payload: a longer one is a
  // kProtocol failure that closes the connection (never an allocation of what the peer claims).
  static constexpr std::size_t kMaxLineBytes = 16u << 20;
  static constexpr std::size_t kMaxFrameBytes = 64u << 20;

  // Connects to the sim API at host:port and reads the server's hello, within timeout_s of wall
  // time. kConnectionRefused when nothing listens, kTimeout, kProtocol when the peer does not
  // greet as a uavsim server (or refuses the connection: `overloaded`). Thread-safe: the calling
  // thread owns the new connection.
  static Result<std::unique_ptr<SimConnection>> connect(const std::string& host, uint16_t port,
                                                        double timeout_s = 10.0);
  // Takes over a connected stream socket (closed by the connection) and reads the hello as
  // connect() does. Thread-safe, as connect().
  static Result<std::unique_ptr<SimConnection>> adopt(int fd, double timeout_s = 10.0);
  ~SimConnection();
  SimConnection(const SimConnection&) = delete;
  SimConnection& operator=(const SimConnection&) = delete;

  // The server's hello ({"hello": "uavsim", "protocol": 1, "ops": [...]}). Owner thread only.
  const nlohmann::json& hello() const;
  // False once the connection is closed, lost or broken by a malformed message. Owner thread only.
  bool connected() const;
  // The descriptor to wait on, for a caller's own poll loop (readable: call poll(0)): the socket,
  // or on the shared-memory stream its wake-up; -1 once closed. Owner thread only.
  int fd() const;

  // Moves what the server sends this connection onto its shared-memory stream (docs/protocol.md,
  // "Shared-memory stream"): the same messages in the same order — a tick and its radio frames
  // (those of a batch subscription) are read from shared memory and handed over as the `tick` and
  // `radio_batch` messages the socket would carry; requests still go on the socket. For a server
  // on this machine that offers it; kUnsupported otherwise (the connection goes on over TCP), the
  // server's refusal as request()'s. Owner thread only.
  Result<void> use_shared_memory(double timeout_s = 10.0);
  bool on_shared_memory() const;

  // Sends req (an object with "op") with the next id and waits up to timeout_s of wall time for its
  // reply; returns the reply's "result" (an empty object when it has none). Failures: the server's
  // error (its code mapped to an Error, message "CODE: message"), kTimeout (the late reply is
  // discarded when it comes), kNotConnected / kConnectionLost, kProtocol (malformed or oversized
  // message: the connection is closed), kInvalidArgument (req not an object). Owner thread only.
  Result<nlohmann::json> request(nlohmann::json req, double timeout_s = 30.0);
  // Sends every request at once (one write, so the server wakes once) and waits up to timeout_s in
  // all for their replies, which it answers in order: one round trip instead of one per request.
  // Sent between a lockstep tick and its done, they all run at that tick. The results in request
  // order, each as request() would give it (a request that is not an object with "op": every result
  // is kInvalidArgument and nothing is sent). Owner thread only.
  std::vector<Result<nlohmann::json>> request_all(std::vector<nlohmann::json> reqs,
                                                  double timeout_s = 30.0);

  // Streamed messages of this kind go to handler as they are read instead of the queue (one
  // handler per kind; an empty function removes it). A handler must not call this connection.
  // Owner thread only.
  void on_message(const std::string& kind, std::function<void(const SimMessage&)> handler);
  // The streamed messages read so far that no handler took, oldest first (the queue is emptied).
  // Owner thread only.
  std::vector<SimMessage> take_messages();
  // Reads and dispatches whatever has arrived, waiting up to timeout_ms for the first bytes (0: do
  // not wait). kConnectionLost when the server closed the connection, kProtocol on a malformed
  // message; ok otherwise, whether or not anything came. Owner thread only.
  Result<void> poll(int timeout_ms);

  // The wrappers below send one request each and return its reply's result, failing as request().
  // Owner thread only.
  // Control (docs/protocol.md, "Control").
  Result<nlohmann::json> status();
  Result<nlohmann::json> pause();
  Result<nlohmann::json> resume();
  // Back to t = 0 with this seed.
  Result<nlohmann::json> reset(uint64_t seed);
  // Pauses and advances the clock by sim_s seconds, replying when done (wall_timeout_s to wait).
  Result<nlohmann::json> step_for(double sim_s, double wall_timeout_s);
  // Subscribes to sim events from the start: the reply's `events` is the backlog, later events
  // stream as `sim_event` messages.
  Result<nlohmann::json> subscribe_events();
  // Ground truth of the trucks (not_available without one: kUnsupported).
  Result<nlohmann::json> truck();

  // Joins the lockstep with this tick period (sim seconds); the server drops the connection's
  // lockstep membership after timeout_s of wall time without a `done`. Ticks stream as `tick`.
  // with_tick: queries ({"op": "vehicles"}, "truck", "balloons", "status", "wind", "gimbal"; at
  // most 8) the server answers at each of this connection's ticks, just before it, as one
  // `tick_results` message ({"time": t, "results": [{"result": ...} or {"error": ...}, ...]} in
  // their order): what the client would ask at every tick, without a round trip while the clock
  // waits.
  Result<nlohmann::json> lockstep_join(double period_s, double timeout_s,
                                       const std::vector<nlohmann::json>& with_tick = {});
  Result<nlohmann::json> lockstep_leave();
  // Done with tick `tick`: optionally busy until a later sim time (detached timing), and the last
  // MAVLink sequence number sent on each vehicle's link ({"uav0": 17}) before this call.
  Result<nlohmann::json> done(int64_t tick, const std::map<std::string, int>& mavlink_seq = {},
                              std::optional<double> busy_until_s = std::nullopt);

  // Sends a radio frame (1-127 bytes) from vehicle to vehicle `to` (-1: broadcast).
  Result<nlohmann::json> radio_send(int vehicle, std::string_view bytes, int to = -1);
  // Frames received by this vehicle (-1: every vehicle) stream as `radio` messages.
  Result<nlohmann::json> radio_subscribe(int vehicle);

 private:
  struct Impl;
  explicit SimConnection(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

// Maps the API's error code ("bad_field", "not_available", ...) to an Error. Thread-safe.
Error sim_api_error(std::string_view code);

}  // namespace uavsim::client
