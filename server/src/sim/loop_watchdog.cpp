#include "sim/loop_watchdog.hpp"

#include <algorithm>

namespace uavsim::server::sim {

std::string LoopActivity::where() const {
  const char* where = where_.load(std::memory_order_relaxed);
  const char* detail = detail_.load(std::memory_order_relaxed);
  std::string out = where != nullptr ? where : "";
  if (detail != nullptr) out += std::string(out.empty() ? "" : ": ") + detail;
  return out;
}

LoopWatchdog::LoopWatchdog(const LoopActivity& activity, WatchdogOptions options)
    : activity_(activity), options_(options) {}

std::optional<LoopStall> LoopWatchdog::poll(double now_s) {
  const uint64_t progress = activity_.progress();
  if (!started_ || progress != seen_progress_) {
    // moving: a stall reported before has ended
    if (reported_) {
      recovered_ = true;
      recovery_for_s_ = now_s - stalled_since_s_;
      longest_stall_s_ = std::max(longest_stall_s_, recovery_for_s_);
    }
    started_ = true;
    reported_ = false;
    seen_progress_ = progress;
    seen_at_s_ = now_s;
    return std::nullopt;
  }
  if (finished_ || reported_ || now_s - seen_at_s_ < options_.stall_s) return std::nullopt;
  reported_ = true;
  stalled_since_s_ = seen_at_s_;
  ++stalls_;
  longest_stall_s_ = std::max(longest_stall_s_, now_s - seen_at_s_);
  return LoopStall{now_s - seen_at_s_, activity_.time_s(), activity_.where()};
}

std::optional<double> LoopWatchdog::take_recovery() {
  if (!recovered_) return std::nullopt;
  recovered_ = false;
  return recovery_for_s_;
}

void LoopWatchdog::stop_requested(double now_s) {
  if (!stop_at_s_) stop_at_s_ = now_s;
}

bool LoopWatchdog::must_exit(double now_s) const {
  return stop_at_s_ && !finished_ && now_s - *stop_at_s_ >= options_.stop_grace_s;
}

}  // namespace uavsim::server::sim
