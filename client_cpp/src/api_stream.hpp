// Reader of the sim API's byte stream (docs/protocol.md): newline-delimited JSON, where a line that
// parses to {"event": "frame", "bytes": N, ...} is followed by exactly N bytes of image data.
// Library internal; the one parser of both readers (SimChannel on the event loop, SimConnection's
// blocking reader). A line over the limits, or a frame header without a usable byte count, ends the
// stream with an error instead of buffering without bound: a peer that never sends a newline, or
// announces a 4 GB frame, must not make the client allocate for ever.
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
  // From inside on_message: ends the stream with this error (the reader's own rule, e.g. a line
  // that is not a JSON object); nothing after the current message is delivered.
  void stop(std::string why) {
    error_ = "sim API: " + std::move(why);
    held_ = false;
  }

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
    while (!held_ && !error_) {
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
          stop("a line longer than " + std::to_string(max_line_bytes_) + " bytes");
        break;
      }
      if (nl - pos > max_line_bytes_) {
        stop("a line longer than " + std::to_string(max_line_bytes_) + " bytes");
        break;
      }
      nlohmann::json j =
          nlohmann::json::parse(std::string_view(buf_.data() + pos, nl - pos), nullptr, false);
      pos = nl + 1;
      const auto ev = j.is_object() ? j.find("event") : j.end();
      if (j.is_object() && ev != j.end() && ev->is_string() && *ev == "frame") {
        // a frame header: exactly `bytes` bytes of image follow (typed lookups: a wrong type is
        // bad input, not an exception)
        const auto n = j.find("bytes");
        if (n == j.end() || !n->is_number_integer() || n->get<std::int64_t>() < 0 ||
            static_cast<std::uint64_t>(n->get<std::int64_t>()) > max_frame_bytes_) {
          stop("a frame header without a usable `bytes` (at most " +
               std::to_string(max_frame_bytes_) + ")");
          break;
        }
        pending_bytes_ = static_cast<std::size_t>(n->get<std::int64_t>());
        pending_header_ = std::move(j);  // (n points into j: read first)
        if (pending_bytes_ > 0) continue;
        on_message(pending_header_, std::string_view());  // an empty frame
        pending_header_ = nullptr;
        continue;
      }
      on_message(j, std::string_view());
    }
    if (error_) {
      buf_.clear();
      return;
    }
    buf_.erase(0, pos);
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
