// A bounded byte queue from the loop thread (which encodes replies and telemetry) to the network
// I/O thread (which writes them to one client's socket). A client that does not read costs only its
// own frames: when the queue is full, whole frames are dropped and counted, the writer never
// blocks. The bytes and the bound are the server's common write buffer (net/write_buffer.hpp);
// dropping the frame is this endpoint's policy at the bound.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string_view>

#include "net/write_buffer.hpp"

namespace uavsim::server::mavlink {

class Outbox {
 public:
  explicit Outbox(std::size_t limit_bytes) : buffer_(limit_bytes) {}

  // Appends one whole frame; false (and counted) when it does not fit or the client is gone.
  // Thread-safe.
  bool push(std::span<const std::uint8_t> frame) {
    const std::string_view bytes(reinterpret_cast<const char*>(frame.data()), frame.size());
    if (buffer_.append(bytes) == net::WriteBuffer::Append::kQueued) return true;
    dropped_frames_.fetch_add(1, std::memory_order_relaxed);
    return false;
  }

  // The bytes for the I/O thread to write.
  net::WriteBuffer& buffer() { return buffer_; }

  // Refuses further frames (the client disconnected). Thread-safe.
  void close() { buffer_.close(); }

  // Frames refused so far (buffer full or closed). Thread-safe.
  std::uint64_t dropped_frames() const { return dropped_frames_.load(std::memory_order_relaxed); }

 private:
  net::WriteBuffer buffer_;
  std::atomic<std::uint64_t> dropped_frames_{0};
};

}  // namespace uavsim::server::mavlink
