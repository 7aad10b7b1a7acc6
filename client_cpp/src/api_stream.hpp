// Reader of the sim API's byte stream (docs/protocol.md): newline-delimited JSON, where a line that parses
// to {"event": "frame", "bytes": N, ...} is followed by exactly N bytes of image data. Library internal.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

namespace uavsim::client {

class ApiStream {
 public:
  // Consumes bytes; calls on_message(json, payload) for each complete message (payload empty unless a
  // frame). Malformed lines are passed as a discarded (non-object) json.
  template <class F>
  void feed(const char* data, std::size_t size, F&& on_message) {
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
      if (nl == std::string::npos) break;
      nlohmann::json j = nlohmann::json::parse(std::string_view(buf_.data() + pos, nl - pos), nullptr, false);
      pos = nl + 1;
      if (j.is_object() && j.value("event", std::string()) == "frame") {
        const auto n = j.value("bytes", std::int64_t{0});
        if (n > 0) {
          pending_header_ = std::move(j);
          pending_bytes_ = static_cast<std::size_t>(n);
          continue;
        }
      }
      on_message(j, std::string_view());
    }
    buf_.erase(0, pos);
  }

  std::string buf_;
  bool held_ = false;
  nlohmann::json pending_header_;
  std::size_t pending_bytes_ = 0;
};

}  // namespace uavsim::client
