// A TCP server for newline-delimited messages with its own I/O thread (poll on non-blocking sockets).
// Lines arrive through callbacks on the I/O thread; replies are queued from any thread with send().
// A line longer than max_line_bytes is reported once and skipped up to its newline; the connection
// stays open. Knows nothing of JSON or the simulation.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <map>
#include <mutex>
#include <string>
#include <thread>

namespace uavsim::server::api {

class LineServer {
 public:
  struct Callbacks {
    std::function<void(uint64_t conn)> on_connect;
    std::function<void(uint64_t conn, std::string line)> on_line;  // without the newline
    std::function<void(uint64_t conn)> on_line_too_long;
    std::function<void(uint64_t conn)> on_disconnect;
  };

  // Binds and listens on bind_address:port (port 0: an ephemeral port). Throws std::runtime_error
  // naming the address and port if that fails (a startup error). Callbacks run on the I/O thread.
  LineServer(const std::string& bind_address, uint16_t port, size_t max_line_bytes, Callbacks callbacks);
  ~LineServer();  // stops the I/O thread and closes every socket
  LineServer(const LineServer&) = delete;
  LineServer& operator=(const LineServer&) = delete;

  void start();  // starts the I/O thread. Call once.
  void stop();   // Thread-safe (not from a callback): stops the I/O thread and closes the sockets.
  uint16_t port() const { return port_; }

  // Queues data for a connection. Thread-safe. False if the connection is gone.
  bool send(uint64_t conn, const std::string& data);
  // Bytes queued for a connection and not yet written to its socket (0 if it is gone). Thread-safe.
  size_t pending_bytes(uint64_t conn);

 private:
  struct Conn {
    int fd = -1;
    std::string in;
    bool discarding = false;  // skipping the rest of an over-long line
    std::string out;          // guarded by out_mutex_
    // being written, I/O thread only: whole batches are swapped out of `out` and written from an offset,
    // so a large frame is neither moved on every partial write nor written with out_mutex_ held (which
    // would stall the threads queueing the next frame)
    std::string sending;
    size_t sent = 0;
    size_t unsent = 0;        // sending.size() - sent, for pending_bytes(); guarded by out_mutex_
  };
  void run();
  void wake();
  void accept_all();
  bool read_conn(uint64_t id, Conn& c);   // false: closed
  bool write_conn(Conn& c);               // false: failed; takes out_mutex_ itself

  Callbacks callbacks_;
  size_t max_line_bytes_;
  int listen_fd_ = -1;
  int wake_fds_[2] = {-1, -1};
  uint16_t port_ = 0;
  std::atomic<bool> stop_{false};
  std::thread thread_;
  std::mutex out_mutex_;               // guards conns_ membership and every Conn::out
  std::map<uint64_t, Conn> conns_;     // membership changes on the I/O thread only
  uint64_t next_id_ = 1;
};

}  // namespace uavsim::server::api
