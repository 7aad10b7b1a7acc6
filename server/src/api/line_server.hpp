// A TCP server for newline-delimited messages on the server's event loop (net/event_loop.hpp): its
// own I/O thread, or one shared with the MAVLink endpoints. Lines arrive through callbacks on the
// I/O thread; replies are queued from any thread with send().
// A line longer than max_line_bytes is reported once and skipped up to its newline; the connection
// stays open. Knows nothing of JSON or the simulation.
//
// Limits: at most max_connections at once (one more is sent the overload line and closed); a
// connection's unsent output is capped at max_pending_bytes, all connections' together at
// max_total_pending_bytes: a connection that would pass either is sent the overload line, reads
// nothing more and is closed once that is written (or after kOverloadGrace_s if it does not read).
// When the process is out of file descriptors, the acceptor's reserve descriptor accepts and closes
// the waiting connection, so the listener never spins (net/tcp_acceptor.hpp).
//
// A peer that shuts down its sending side (EOF) has its last line delivered and on_disconnect
// called, but keeps receiving until the owner calls close_when_sent(): replies to its last requests
// still reach it.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <span>
#include <string>

#include "net/event_loop.hpp"
#include "net/tcp_acceptor.hpp"
#include "net/write_buffer.hpp"

namespace uavsim::server::api {

class LineServer {
 public:
  struct Callbacks {
    std::function<void(uint64_t conn)> on_connect;
    std::function<void(uint64_t conn, std::string line)> on_line;  // without the newline
    std::function<void(uint64_t conn)> on_line_too_long;
    std::function<void(uint64_t conn)> on_disconnect;
    // after the lines of one read (what the peer had sent by then), before its on_disconnect
    std::function<void(uint64_t conn)> on_read_end;
    // a binary request from a connection's Intake (its type and bytes, valid during the call)
    std::function<void(uint64_t conn, std::uint16_t type, std::span<const std::uint8_t> payload)>
        on_record;
  };

  // Binds and listens on bind_address:port (port 0: an ephemeral port). Throws std::runtime_error
  // naming the address and port if that fails (a startup error). Callbacks run on the I/O thread:
  // loop's if given (it must outlive this server; its owner starts it), else a loop of its own.
  struct Limits {
    size_t max_line_bytes = 1u << 20;
    size_t max_connections = 64;
    size_t max_pending_bytes = 64u << 20;
    size_t max_total_pending_bytes = 256u << 20;
    std::string overload_line;  // sent before an overload drop (with its newline); empty: none
  };
  LineServer(const std::string& bind_address, uint16_t port, Limits limits, Callbacks callbacks,
             net::EventLoop* loop = nullptr);
  ~LineServer();  // stop()
  LineServer(const LineServer&) = delete;
  LineServer& operator=(const LineServer&) = delete;

  // Where a connection's output goes instead of its socket (the sim API's shared-memory stream,
  // api/shm_transport.hpp). write() gets whole messages in order, with the output lock held (it
  // must not block); false closes the connection as overloaded.
  class Diversion {
   public:
    virtual ~Diversion() = default;
    // work_ahead: data the reader may work on before its next tick (a camera frame), which wakes
    // even a reader that said it waits for nothing but that tick (ShmTransport's quiet done)
    virtual bool write(const std::string& data, bool work_ahead) = 0;
    virtual size_t pending_bytes() const = 0;  // written and not yet taken by the peer
  };

  // A second way in for a connection's requests (the sim API's request ring, api/request_ring.hpp),
  // read on the I/O thread while its descriptor is readable: its lines go to on_line (or
  // on_line_too_long) and its binary requests to on_record, in its own order, then on_read_end, as
  // for a read of the socket.
  class Intake {
   public:
    virtual ~Intake() = default;
    virtual int fd() const = 0;  // readable when requests may wait
    struct Sink {
      std::function<void(std::string line)> line;  // without its newline
      std::function<void(std::uint16_t type, std::span<const std::uint8_t> payload)> record;
    };
    // Reads what waits. False with *why when the peer broke it: the connection is then closed as
    // overloaded, with *why on stderr.
    virtual bool read(const Sink& sink, std::string* why) = 0;
  };
  // Starts accepting (and its own I/O thread, if it has one). Call once.
  void start();
  // Closes every socket; no callback runs after it returns. Thread-safe (not from a callback).
  void stop();
  uint16_t port() const { return port_; }

  // Queues data for a connection. Thread-safe. False if the connection is gone or overloaded (the
  // data is dropped and the connection closed after the overload line). work_ahead: see Diversion.
  bool send(uint64_t conn, const std::string& data, bool work_ahead = false);
  // Closes a connection once everything queued for it has been written (after its EOF).
  // Thread-safe.
  void close_when_sent(uint64_t conn);
  // From now on send() hands conn's output to diversion (what is queued already still goes to the
  // socket); the socket is still read. False if conn is gone. Thread-safe.
  bool divert(uint64_t conn, std::shared_ptr<Diversion> diversion);
  // From now on conn's requests come through intake too (the peer keeps to one of them: the two
  // have no order between them). The server lets go of it when conn closes or has sent its EOF.
  // False if conn is gone. Thread-safe; waits for the I/O thread.
  bool add_intake(uint64_t conn, std::shared_ptr<Intake> intake);
  // Closes conn as overloaded (the overload line, then the socket), as when its output passes its
  // cap: for a diversion that failed outside send(). Thread-safe.
  void close_overloaded(uint64_t conn);
  // While held, send() queues without waking the I/O thread; release_wakeups() wakes it once if
  // anything was queued meanwhile. The sim API holds them for one pass of its gate, so a
  // connection's messages of that pass (replies, radio batch, tick) leave in one write and reach
  // the client as one wake-up instead of one each. Never hold across a wait. I/O thread (one holder
  // at a time).
  void hold_wakeups() { wakeups_held_.store(true); }
  void release_wakeups();
  // Accepts that failed for want of file descriptors. Thread-safe.
  uint64_t fd_exhausted_accepts() const { return acceptor_->exhausted_accepts(); }
  // Bytes queued for a connection and not yet written to its socket (0 if it is gone). Thread-safe.
  size_t pending_bytes(uint64_t conn);
  // The IPv4 address of a connection's peer ("" if it is gone). Thread-safe.
  std::string peer_address(uint64_t conn) const;

 private:
  struct Conn {
    explicit Conn(int socket, size_t limit_bytes) : fd(socket), out(limit_bytes) {}
    int fd = -1;
    std::string in;
    std::string peer;                      // the peer's IPv4 address
    std::shared_ptr<Diversion> diversion;  // divert(); guarded by out_mutex_
    std::shared_ptr<Intake> intake;        // add_intake(); I/O thread only
    bool discarding = false;               // skipping the rest of an over-long line
    net::WriteBuffer out;                  // bounded by max_pending_bytes
    std::uint32_t interest = 0;            // the epoll events watched; I/O thread only
    bool read_closed = false;              // EOF seen, on_disconnect called; I/O thread only
    bool close_requested = false;          // close_when_sent(); guarded by out_mutex_
    bool overloaded = false;               // overload line queued, closing; guarded by out_mutex_
    double overloaded_at_s = 0.0;
  };
  enum class ReadResult { kOpen, kEof, kFailed };
  void wake() {
    if (net::Waker* w = waker_.load()) w->wake();  // before start(): served once it runs
  }
  void on_accept(int fd, const std::string& peer);
  void on_events(uint64_t id, std::uint32_t events);
  void serve_all();  // writes every connection, closes the finished ones
  ReadResult read_conn(uint64_t id, Conn& c);
  void on_intake(uint64_t id);
  void drop_intake(Conn& c);  // I/O thread
  bool write_conn(Conn& c);  // false: failed; takes out_mutex_ itself
  void watch_for(Conn& c);   // reading while open, writing while output waits
  void close_conn(uint64_t id);
  void mark_overloaded(Conn& c);  // out_mutex_ held
  bool finished(const Conn& c);   // takes out_mutex_ itself: closing and all written (or too late)
  void teardown();                // I/O thread: every socket closed, callbacks off

  Callbacks callbacks_;
  Limits limits_;
  size_t max_line_bytes_;
  size_t total_pending_ = 0;  // sum of every Conn's unwritten output; guarded by out_mutex_
  std::unique_ptr<net::EventLoop> own_loop_;  // without a shared loop
  net::EventLoop& loop_;
  net::FdReserve fd_reserve_;
  std::unique_ptr<net::TcpAcceptor> acceptor_;  // lives as long as the server (its counter)
  std::atomic<net::Waker*> waker_{nullptr};     // output queued, a close requested: serve_all()
  std::size_t tick_ = 0;
  std::atomic<int> overloaded_conns_{0};  // the tick checks their grace period while any
  // sends queue without waking the I/O thread while held (hold_wakeups)
  std::atomic<bool> wakeups_held_{false};
  std::atomic<bool> wake_deferred_{false};  // a send() while held: release_wakeups() wakes
  uint16_t port_ = 0;
  std::atomic<bool> stopped_{false};
  mutable std::mutex out_mutex_;    // guards conns_ membership and the Conn fields marked so
  std::map<uint64_t, Conn> conns_;  // membership changes on the I/O thread only
  uint64_t next_id_ = 1;
};

}  // namespace uavsim::server::api
