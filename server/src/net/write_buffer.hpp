// The outgoing bytes of one connection: queued whole by any thread, written by the I/O thread as
// far as the socket takes them, with a bound on what may wait. What happens to a connection that
// reaches the bound is its owner's policy: the MAVLink endpoint drops the frame
// (mavlink/outbox.hpp), the sim API sends an overload line and closes (api/line_server.hpp).
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <mutex>
#include <string>
#include <string_view>

namespace uavsim::server::net {

class WriteBuffer {
 public:
  enum class Append { kQueued, kFull, kClosed };
  enum class Write { kDone, kBlocked, kFailed };  // all written; socket full; socket error

  // limit_bytes: the most unwritten bytes (queued, plus taken for writing and not yet in the
  // socket)
  explicit WriteBuffer(std::size_t limit_bytes) : limit_bytes_(limit_bytes) {}

  // Queues data whole, or nothing if that would pass the limit (kFull) or the buffer is closed.
  // Thread-safe; never blocks on the socket.
  Append append(std::string_view data);
  // Queues data even past the limit (a last message before the owner closes). Thread-safe.
  void append_unbounded(std::string_view data);

  // Writes to the stream socket fd until everything queued is written or the socket is full
  // (non-blocking, no SIGPIPE); the bytes are swapped out in batches, so the lock is not held
  // during the system call and a large batch is never moved on a partial write. Adds the bytes
  // written to *written. I/O thread (one writer).
  Write write_to(int fd, std::size_t* written);
  // Moves the queued bytes into out (for datagram sockets, which send them in their own pieces).
  // I/O thread.
  void take_queued(std::string& out);

  // Bytes queued or taken and not yet written. Thread-safe.
  std::size_t unwritten() const;
  // True if bytes are queued for the writer; a cheap hint without the lock. Thread-safe.
  bool has_queued() const { return has_queued_.load(std::memory_order_acquire); }
  // Refuses every later append and drops what is queued. Thread-safe.
  void close();

 private:
  const std::size_t limit_bytes_;
  mutable std::mutex mutex_;
  std::string queued_;         // guarded by mutex_
  std::size_t in_flight_ = 0;  // sending_.size() - sent_, for unwritten(); guarded by mutex_
  bool closed_ = false;        // guarded by mutex_
  std::atomic<bool> has_queued_{false};
  // the batch being written, writer only
  std::string sending_;
  std::size_t sent_ = 0;
};

}  // namespace uavsim::server::net
