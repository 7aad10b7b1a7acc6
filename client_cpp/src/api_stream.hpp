// Reader of the sim API's byte stream (docs/protocol.md): newline-delimited JSON, where a line that
// parses to {"event": "frame", "bytes": N, ...} is followed by exactly N bytes of image data.
// Library internal. A line or a frame over the limits (SimConnection's blocking reader's, by
// default) ends the stream with an error instead of buffering without bound: a peer that never
// sends a newline, or announces a 4 GB frame, must not make the client allocate for ever.
#pragma once

#include <cstddef>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>

#include "uavsim/client/sim_connection.hpp"

namespace uavsim::client {

class ApiStream {
 public:
  explicit ApiStream(std::size_t max_line_bytes = SimConnection::kMaxLineBytes,
                     std::size_t max_frame_bytes = SimConnection::kMaxFrameBytes)
      : max_line_bytes_(max_line_bytes), max_frame_bytes_(max_frame_bytes) {}

  // Why the stream stopped (a line or frame over the limits); nothing while it is fine. Once set,
  // feed() drops everything: the connection is to be closed.
  const std::optional<std::string>& error() const { return error_; }

  // Consumes bytes; calls on_message(json, payload) for each complete message (payload empty unless
  // a frame). Malformed lines are passed as a discarded (non-object) json.
  template <class F>
  void feed(const char* data, std::size_t size, F&& on_message) {
    if (error_) return;
    buf_.append(data, size);
    pump(on_message);
  }

  // hold(), from inside on_message: the messages after this one stay buffered until resume()
  // (a pipelined lockstep loop works on a tick before it looks at what came after it).
  void hold() { held_ = true; }
  bool held() const { return held_; }
  template <class F>
  void resume(F&& on_message) {
    held_ = false;
    pump(on_message);
  }

 private:
  template <class F>
  void pump(F& on_message) {
    std::size_t pos = 0;
    while (!held_) {
      if (pending_bytes_ > 0) {
        if (buf_.size() - pos < pending_bytes_) break;
        const std::string_view payload(buf_.data() + pos, pending_bytes_);
        pos += pending_bytes_;
        pending_bytes_ = 0;
        on_message(pending_header_, payload);
        pending_header_ = nullptr;
        continue;
      }
      const std::size_t nl = buf_.find('\n', pos);
      if (nl == std::string::npos) {
        if (buf_.size() - pos > max_line_bytes_)
          fail("a line longer than " + std::to_string(max_line_bytes_) + " bytes");
        break;
      }
      if (nl - pos > max_line_bytes_) {
        fail("a line longer than " + std::to_string(max_line_bytes_) + " bytes");
        break;
      }
      nlohmann::json j =
          nlohmann::json::parse(std::string_view(buf_.data() + pos, nl - pos), nullptr, false);
      pos = nl + 1;
      if (j.is_object() && j.value("event", std::string()) == "frame") {
        const auto n = j.value("bytes", std::int64_t{0});
        if (n > 0 && static_cast<std::uint64_t>(n) > max_frame_bytes_) {
          fail("a frame of " + std::to_string(n) + " bytes (at most " +
               std::to_string(max_frame_bytes_) + ")");
          break;
        }
        if (n > 0) {
          pending_header_ = std::move(j);
          pending_bytes_ = static_cast<std::size_t>(n);
          continue;
        }
      }
      on_message(j, std::string_view());
    }
    if (error_) {
      buf_.clear();
      return;
    }
    buf_.erase(0, pos);
  }

  void fail(std::string why) {
    error_ = "sim API: " + std::move(why);
    held_ = false;
  }

  std::string buf_;
  bool held_ = false;
  nlohmann::json pending_header_;
  std::size_t pending_bytes_ = 0;
  std::size_t max_line_bytes_;
  std::size_t max_frame_bytes_;
  std::optional<std::string> error_;
};

}  // namespace uavsim::client
