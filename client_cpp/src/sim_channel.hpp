// SimChannel: the sim API (docs/protocol.md) as the library's loop-driven modules speak it. One
// connection, read without blocking whenever the event loop finds it readable: requests get their
// reply through a callback (matched by id), streamed messages go to sinks (camera frames by camera
// name, other events by event name), and what nothing takes goes to the owner's `unrouted` handler.
//
// There are two such connections, both carrying the same messages the same way:
//   * the lockstep loop's own connection (EventLoop under lockstep, reached through LoopServices):
//     the loop reads it at ticks and handles the tick messages (unrouted); in pipelined lockstep it
//     holds what is sent during a tick's work (hold_outputs) and what arrives after a tick
//     (hold_input) until the tick's work is done;
//   * a connection of its own (connect()), watched by the loop on the host clock, e.g. a
//     CameraSubscriber's when the loop has no simulator connection.
// So a module subscribes, is answered and is fed the same way on either clock; the clock only
// decides when the bytes are read.
//
// On the server's machine the lockstep loop's connection may read from the shared-memory stream
// (use_ring, shm_stream.hpp) instead of its socket: the same messages in the same order, but a tick
// and its radio frames as one binary record, handed to the radio sinks and as a tick message.
//
// SimConnection (include/uavsim/client/sim_connection.hpp) is the blocking, public counterpart for
// launchers and tests. Library internal; loop thread only.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <span>
#include <string>
#include <string_view>

#include "api_stream.hpp"
#include "shm_stream.hpp"
#include "uavsim/client/event_loop.hpp"
#include "uavsim/client/result.hpp"

namespace uavsim::client {

class SimChannel {
 public:
  using Json = nlohmann::json;
  using ReplyHandler = std::function<void(const Json& reply)>;
  using EventSink = std::function<void(const Json& event)>;
  using FrameSink = std::function<void(const Json& header, std::string_view bytes)>;
  // a received radio frame of a tick record (shared-memory stream); on TCP they come as radio_batch
  // events to the event sinks
  using RadioSink = std::function<void(const common::shm::RadioFrame& frame)>;
  // a message no sink or reply handler takes (the lockstep loop's tick, lockstep_dropped, reset and
  // the replies to `done`)
  using Unrouted = std::function<void(const Json& message)>;

  SimChannel() = default;
  ~SimChannel();  // closes
  SimChannel(const SimChannel&) = delete;
  SimChannel& operator=(const SimChannel&) = delete;

  // Takes over a connected, non-blocking socket whose hello has been read; sends wait at most
  // send_timeout_s of wall time. The owner has the loop watch fd() and calls read_available().
  void open(int fd, double send_timeout_s, Unrouted unrouted);
  // Connects to the sim API at address ("host:port"), reads the hello (timeout_s of wall time each)
  // and has `loop` read the connection as bytes arrive (it closes itself when the peer does).
  // kInvalidArgument for a bad address, else the connection's failure.
  static Result<std::unique_ptr<SimChannel>> connect(EventLoop& loop, const std::string& address, double timeout_s);
  // Closes the connection (unwatching it if connect() watched it); held output is discarded, reply
  // handlers are dropped unanswered. Sinks stay registered.
  void close();
  bool is_open() const { return fd_ >= 0; }
  // The descriptor to wait on for input: the socket, or the shared-memory stream's wake-up.
  int fd() const { return ring_ ? ring_->wake_fd() : fd_; }
  // From now on input comes from this shared-memory stream, not the socket, and requests go into
  // its request ring if it has one (else on the socket). Call once the reply that offered it has
  // been read: nothing follows it on the socket.
  void use_ring(std::unique_ptr<ShmStream> ring) { ring_ = std::move(ring); }
  bool on_ring() const { return ring_ != nullptr; }
  // Whether requests go through a request ring, where radio_send and done have a binary form.
  bool has_request_ring() const { return ring_ && ring_->has_requests(); }
  // The owner wakes the server for what it wrote into the request ring only before it sleeps
  // (flush_request_wakeup): a lockstep loop's requests of a tick and its done wake the server once.
  void defer_request_wakeups() { defer_wakeups_ = true; }
  void flush_request_wakeup() {
    if (ring_) ring_->flush_wakeup();
  }

  // ---- sending
  // Sends request (an object with "op") with the next id; on_reply gets the whole reply when it is
  // read. False when the connection is closed or the send fails (no handler is kept then).
  bool request(Json request, ReplyHandler on_reply);
  // One line (no newline), held while outputs are held. False when closed or the send fails.
  bool send(const std::string& line);
  // One line, never held (the lockstep `done`).
  bool send_now(const std::string& line);
  // A binary request into the request ring (common/shm_requests.hpp: its payload), never held: the
  // server answers it only if it refuses it, to the standing handler of its tag (tag 0: unrouted).
  // False without a request ring, or when the write fails.
  bool send_binary(common::shm::RecordType type, std::span<const std::uint8_t> payload);
  // Whether lines are held now (hold_outputs): a binary request must not overtake them.
  bool outputs_held() const { return outputs_held_; }
  // A handler for the refusals of binary requests sent with the returned tag (never 0), until
  // removed.
  std::uint32_t add_standing_reply(ReplyHandler handler);
  void remove_standing_reply(std::uint32_t tag) { standing_replies_.erase(tag); }
  // Lines sent from now on are kept until release_outputs(), which sends them (false if that fails).
  void hold_outputs() { outputs_held_ = true; }
  bool release_outputs();

  // ---- receiving
  enum class ReadResult {
    kOk,      // read all there was, or stopped because a handler held the input or closed the channel
    kClosed,  // the peer closed the connection
    kError,   // recv failed (why says how)
  };
  // Reads what has arrived (without blocking) and routes every whole message in it.
  ReadResult read_available(std::string* why);
  // Routes the whole messages in these bytes (e.g. what was read past the hello).
  void feed(const char* data, std::size_t size);
  // From inside a handler: the messages after this one stay unread (buffered) until resume_input().
  void hold_input() { stream_.hold(); }
  // Routes what was held, and on a shared-memory stream what waits in the ring (which has no
  // readiness of its own to report it): the ring's failure as read_available's.
  ReadResult resume_input(std::string* why);

  // ---- routing
  // Frames of this camera go to sink. False (nothing changed) when the camera already has one.
  bool add_frame_sink(const std::string& camera, FrameSink sink);
  void remove_frame_sink(const std::string& camera);
  // Events named `event` go to sink (every sink of that name sees each one). Returns the sink's id.
  std::uint64_t add_event_sink(const std::string& event, EventSink sink);
  // Radio frames of tick records go to sink. Returns the sink's id (remove_event_sink removes it).
  std::uint64_t add_radio_sink(RadioSink sink);
  void remove_event_sink(std::uint64_t id);  // nothing if there is none (an event or radio sink)
  // A tick record's tick goes to handler instead of as a tick message to the unrouted handler (the
  // lockstep loop's, which then parses nothing for it).
  using TickHandler = std::function<void(std::int64_t tick, double time_s)>;
  void set_tick_handler(TickHandler handler) { tick_handler_ = std::move(handler); }

 private:
  void route(const Json& message, std::string_view payload);
  void on_io(std::uint32_t what);
  // the shared-memory stream's records, until it is empty or the input is held
  ReadResult read_ring(std::string* why);
  bool route_tick(const std::vector<std::uint8_t>& payload, std::string* why);

  int fd_ = -1;
  double send_timeout_s_ = 10.0;
  EventLoop* watched_by_ = nullptr;  // connect(): the loop that watches fd_
  Unrouted unrouted_;
  ApiStream stream_;
  bool outputs_held_ = false;
  std::string held_;
  // sends whole lines (each with its newline) on the request ring or the socket
  bool send_lines(const std::string& lines);
  // one record into the request ring (false, said on stderr, when it cannot be written)
  bool write_request(common::shm::RecordType type, std::span<const std::uint8_t> payload);
  std::map<std::string, ReplyHandler> reply_handlers_;
  std::map<std::uint32_t, ReplyHandler> standing_replies_;  // by tag ("b<tag>" ids)
  std::uint32_t next_standing_tag_ = 1;
  bool defer_wakeups_ = false;  // defer_request_wakeups()
  TickHandler tick_handler_;
  std::uint64_t next_request_id_ = 1;
  std::map<std::string, FrameSink> frame_sinks_;
  std::multimap<std::string, std::pair<std::uint64_t, EventSink>> event_sinks_;
  std::map<std::uint64_t, RadioSink> radio_sinks_;
  std::unique_ptr<ShmStream> ring_;
  common::shm::RingReader::Record record_;  // reused: its buffer keeps its capacity
  common::shm::TickRecord tick_buffer_;     // reused likewise, by route_tick
  std::uint64_t next_event_sink_ = 1;
};

// Sends request on channel and runs loop until its reply is read (timeout_s on the loop clock) or
// the channel closes. The whole reply ({"ok": ..., "result" | "error": ...}); kConnectionLost "<who>:
// no simulator connection" when it cannot be sent or the connection closes first, or the wait's
// failure. Loop thread only.
Result<nlohmann::json> call_and_wait(EventLoop& loop, SimChannel& channel, nlohmann::json request,
                                     double timeout_s, const std::string& who);

// A reply's error as "code: message" ("?" for what is missing).
std::string reply_error_text(const nlohmann::json& reply);

}  // namespace uavsim::client
