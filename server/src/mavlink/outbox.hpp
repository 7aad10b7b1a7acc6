// A bounded byte queue from the loop thread (which encodes replies and telemetry) to the network I/O thread
// (which writes them to one client's socket). A client that does not read costs only its own frames: when
// the queue is full, whole frames are dropped and counted, the writer never blocks.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <mutex>
#include <span>
#include <vector>

namespace uavsim::server::mavlink {

class Outbox {
 public:
  explicit Outbox(std::size_t limit_bytes) : limit_bytes_(limit_bytes) {}

  // Appends one whole frame; false (and counted) when it does not fit or the client is gone. Thread-safe.
  bool push(std::span<const std::uint8_t> frame) {
    std::lock_guard lock(mutex_);
    if (closed_ || bytes_.size() + frame.size() > limit_bytes_) {
      ++dropped_frames_;
      return false;
    }
    bytes_.insert(bytes_.end(), frame.begin(), frame.end());
    pending_.store(true, std::memory_order_release);
    return true;
  }

  // Moves the queued bytes into out (which must be empty). Thread-safe (called by the I/O thread).
  void take(std::vector<std::uint8_t>& out) {
    std::lock_guard lock(mutex_);
    out.swap(bytes_);
    bytes_.clear();
    pending_.store(false, std::memory_order_release);
  }

  // True when bytes are waiting; a cheap hint for the I/O thread. Thread-safe.
  bool pending() const { return pending_.load(std::memory_order_acquire); }

  // Refuses further frames (the client disconnected). Thread-safe.
  void close() {
    std::lock_guard lock(mutex_);
    closed_ = true;
    bytes_.clear();
  }

  // Frames refused so far (buffer full or closed). Thread-safe.
  std::uint64_t dropped_frames() const {
    std::lock_guard lock(mutex_);
    return dropped_frames_;
  }

 private:
  const std::size_t limit_bytes_;
  mutable std::mutex mutex_;
  std::vector<std::uint8_t> bytes_;  // guarded by mutex_
  bool closed_ = false;              // guarded by mutex_
  std::uint64_t dropped_frames_ = 0; // guarded by mutex_
  std::atomic<bool> pending_{false};
};

}  // namespace uavsim::server::mavlink
