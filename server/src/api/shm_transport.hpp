// The sim API's shared-memory stream (docs/protocol.md, "Shared-memory stream"): for a client on
// the server's machine, everything the server sends a connection goes into a ring in shared memory
// (common/shm_ring.hpp) instead of its TCP socket, written by the thread that sends it (no hop
// through the I/O thread), with one wake-up per gate pass at most; a lockstep tick travels as one
// binary record with the radio frames for it (no JSON, no base64).
//
// Negotiation (op lockstep_shm, ApiServer): the server creates, 0600 and O_EXCL, a shared-memory
// object /dev/shm/uavsim-TOKEN and a FIFO /dev/shm/uavsim-TOKEN.wake (TOKEN: 128 random bits in
// hex; the API is TCP, so no descriptor can be passed), replies with TOKEN on TCP, and diverts the
// connection's output to the ring from the next message on. The client maps both and unlinks the
// names; the server unlinks them too when the connection ends (whichever comes first). The FIFO is
// the wake-up the client's event loop can wait on beside its other descriptors (a futex could not
// be); the server holds its only write end, so the client sees a hang-up when the connection ends
// or the server dies.
//
// A client that asks for it also gets a request ring (api/request_ring.hpp) in the same region, and
// from then on sends every request there, `done` included: a request sent between a tick and its
// `done` must run before the `done` (the lockstep contract, point 3), and one ordered channel keeps
// that without a second sequencing scheme. Otherwise its requests stay on TCP.
//
// A lockstep client that waits for nothing but its next tick says so in its `done` ("quiet"): once
// that done is accepted (quiet_until_tick), what its ring gets wakes nobody until its next tick
// record, which wakes it once with all of it (the replies to the requests it sent with the done,
// events); but a camera frame (LineServer::send's work_ahead) wakes it as it comes, so that its
// vision runs while the simulation steps on. Anything that may leave the client waiting for
// something other than that tick ends the quiet with a wake-up: a further request of the connection
// (its reply may be awaited), the clock idling paused, its leaving the lockstep (a drop, a
// disconnect), a reset, the server stopping (end_quiet, end_quiet_all).
//
// A client that stops reading (the ring full), or writes into the ring what the protocol forbids
// (its read position outside what was written), is dropped: its connection is closed as overloaded
// with a message on stderr naming it, it leaves lockstep, and the server goes on.
//
// Thread contract: offer, activate, attached, set_tick_radio, send_tick, release_wakeups,
// quiet_until_tick and on_disconnect on the loop thread; end_quiet and end_quiet_all from any
// thread; the rings' writes (LineServer::Diversion) from any thread that sends, serialised by each
// ring's mutex, which also guards its wake-up state (owed, quiet) against release_wakeups.
#pragma once

#include <atomic>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "api/line_server.hpp"
#include "radio/radio_channel.hpp"

namespace uavsim::server::api {

class ShmTransport {
 public:
  // The ring a client gets when it names none: a tick's radio and events many times over, and a
  // dozen 640 x 480 colour frames.
  static constexpr std::size_t kDefaultRingBytes = std::size_t{16} << 20;

  explicit ShmTransport(LineServer& server);
  ~ShmTransport();
  ShmTransport(const ShmTransport&) = delete;
  ShmTransport& operator=(const ShmTransport&) = delete;

  // The request ring a client gets when it asks for one: many ticks of a flock agent's requests,
  // and a request line of the longest the API takes (ApiConfig::max_line_bytes, 1 MiB).
  static constexpr std::size_t kDefaultRequestRingBytes = std::size_t{2} << 20;

  // Creates conn's ring (ring_bytes: a power of two in [64 KiB, 256 MiB], checked by the caller)
  // and, unless request_ring_bytes is 0, its request ring after it in the same region (likewise;
  // api/request_ring.hpp), and returns what the client needs to map them ({token, ring_bytes,
  // version[, request_ring_bytes]}); nullopt with *why when the system refuses (no /dev/shm, out
  // of memory). Output still goes to TCP until activate().
  std::optional<nlohmann::json> offer(uint64_t conn, std::size_t ring_bytes,
                                      std::size_t request_ring_bytes, std::string* why);
  // From now on conn's output goes to its offered ring, and its requests come through its request
  // ring as well as TCP. Call right after sending the offer's reply.
  void activate(uint64_t conn);
  // Whether conn's output goes to a ring.
  bool attached(uint64_t conn) const;
  // The radio frames that arrived for conn since its last tick, for the tick record send_tick
  // writes next (RadioOps, at before_tick).
  void set_tick_radio(uint64_t conn, std::vector<radio::Delivery> frames);
  // Writes conn's tick as one record with the radio frames given for it. False (nothing written) if
  // conn is not on a ring; a ring that cannot take it drops the connection (see above).
  bool send_tick(uint64_t conn, int64_t tick, double time_s);
  // While held, the rings' wake-ups wait for release_wakeups(): a gate pass wakes each client once.
  void hold_wakeups();
  void release_wakeups();
  // conn's quiet `done` was accepted: until its next tick record (send_tick) or end_quiet, what its
  // ring gets is read with that tick, and the wake-up this gate pass owes it (for the replies
  // before the done) is put off to it as well. Nothing if conn is not on a ring.
  void quiet_until_tick(uint64_t conn);
  // conn may be waiting for what comes next: it is woken for what was written while it was quiet
  // (at the end of the gate pass while wake-ups are held) and for every record from now on.
  void end_quiet(uint64_t conn);
  void end_quiet_all();
  void on_disconnect(uint64_t conn);
  // Connections that have used a ring since the start (for the server's exit line and tests).
  uint64_t activated_total() const { return activated_total_.load(); }
  // Wake-up bytes written into the rings' FIFOs since the start, all rings together (for tests).
  uint64_t wakeups_total() const { return shared_->wakeups.load(); }

 private:
  class Ring;
  std::shared_ptr<Ring> ring_of(uint64_t conn) const;
  LineServer& server_;
  // what the rings share with the transport (a ring may outlive it in the LineServer's hands)
  struct Shared {
    std::atomic<bool> held{false};  // hold_wakeups() .. release_wakeups()
    std::atomic<uint64_t> wakeups{0};
  };
  std::shared_ptr<Shared> shared_ = std::make_shared<Shared>();
  mutable std::mutex mutex_;  // guards rings_ (release_wakeups may race a send on another thread)
  std::map<uint64_t, std::shared_ptr<Ring>> rings_;
  std::map<uint64_t, std::shared_ptr<Ring>> offered_;  // loop thread only
  std::atomic<uint64_t> activated_total_{0};
};

}  // namespace uavsim::server::api
