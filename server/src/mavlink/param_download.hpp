// One client's PARAM_REQUEST_LIST download as a state machine: the whole table, in the flight
// controller's fixed order (the param_index), paced over the control steps so that a download never
// fills a client's outbox at once. Pure: the link sends the indices a step gives.
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace uavsim::server::mavlink {

class ParamDownload {
 public:
  static constexpr std::size_t kPerStep = 16;  // 16 per control step = 8000/s at 500 Hz

  // PARAM_REQUEST_LIST: (re)starts from index 0.
  void start() { next_ = 0; }
  bool active() const { return next_.has_value(); }

  // Calls send(index) for the next at most kPerStep of count parameters; the download ends after
  // the last one.
  template <class F>
  void take(std::size_t count, F&& send) {
    if (!next_) return;
    for (std::size_t i = 0; i < kPerStep && *next_ < count; ++i) send((*next_)++);
    if (*next_ >= count) next_.reset();
  }

 private:
  std::optional<std::size_t> next_;  // next index; none: no download
};

// The param_index of a parameter by name, if it exists. Thread-safe (pure).
inline std::optional<std::size_t> param_index(const std::vector<std::string>& names,
                                              std::string_view name) {
  for (std::size_t i = 0; i < names.size(); ++i) {
    if (names[i] == name) return i;
  }
  return std::nullopt;
}

}  // namespace uavsim::server::mavlink
