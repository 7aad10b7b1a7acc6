// What the loop thread is doing, and a watchdog that notices when it stops doing anything.
//
// A request that sends the loop into an endless computation stops the whole world: no step, no API
// reply, and a SIGTERM whose flag the loop never reads again. LoopActivity is the loop's trail — a
// progress counter each schedule entry and each pass of a waiting gate moves, the name of the entry
// it is in (and a detail such as the API op), the sim time of its step — written with relaxed
// atomics (a store per entry) and readable from any thread. LoopWatchdog reads that trail on a
// clock of its own: a counter that has not moved for stall_s is a stall, reported once with where
// the loop is; and after a stop request, a loop that has not left within stop_grace_s is one the
// process must leave without.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>

namespace uavsim::server::sim {

class LoopActivity {
 public:
  // The loop enters a piece of work named where (a string that outlives the stepping). Loop thread.
  void enter(const char* where) {
    where_.store(where, std::memory_order_relaxed);
    detail_.store(nullptr, std::memory_order_relaxed);
    beat();
  }
  // What inside it (an API op's name; a long-lived string, or nullptr). Loop thread.
  void set_detail(const char* detail) { detail_.store(detail, std::memory_order_relaxed); }
  // Progress without a change of place (a waiting gate's pass). Loop thread.
  void beat() { progress_.fetch_add(1, std::memory_order_relaxed); }
  // The sim time of the step being run. Loop thread.
  void set_time(double time_s) { time_s_.store(time_s, std::memory_order_relaxed); }

  // Thread-safe.
  uint64_t progress() const { return progress_.load(std::memory_order_relaxed); }
  double time_s() const { return time_s_.load(std::memory_order_relaxed); }
  // "queued_tasks/api: radio_send" style: the entry and its detail (empty before the first step).
  std::string where() const;

 private:
  std::atomic<uint64_t> progress_{0};
  std::atomic<const char*> where_{nullptr};
  std::atomic<const char*> detail_{nullptr};
  std::atomic<double> time_s_{0.0};
};

struct WatchdogOptions {
  double stall_s = 10.0;      // no progress this long (wall time) is a stall
  double stop_grace_s = 5.0;  // after a stop request, the loop has this long to leave
};

// A stall, as the watchdog reports it.
struct LoopStall {
  double for_s = 0.0;   // wall seconds without progress
  double time_s = 0.0;  // the sim time the loop is stuck at
  std::string where;    // LoopActivity::where()
};

// The watchdog's decisions, on wall times the caller passes in (a thread in the server, a fake
// clock in tests). One caller thread.
class LoopWatchdog {
 public:
  LoopWatchdog(const LoopActivity& activity, WatchdogOptions options);

  // Looks at the loop at now_s: a stall the first time the loop has made no progress for stall_s
  // (then nothing until it moves again), nullopt otherwise.
  std::optional<LoopStall> poll(double now_s);
  // The stall that poll reported, if the loop has moved since: how long it lasted. Resets it.
  std::optional<double> take_recovery();
  // A stop was requested at now_s (the first call counts).
  void stop_requested(double now_s);
  // True when a stop was requested more than stop_grace_s before now_s and the loop has not
  // finished (loop_finished) since: the process should exit without it.
  bool must_exit(double now_s) const;
  // The loop thread has left its loop: nothing more to watch.
  void loop_finished() { finished_ = true; }

  const LoopActivity& activity() const { return activity_; }
  size_t stalls() const { return stalls_; }
  double longest_stall_s() const { return longest_stall_s_; }

 private:
  const LoopActivity& activity_;
  WatchdogOptions options_;
  uint64_t seen_progress_ = 0;
  double seen_at_s_ = 0.0;
  bool started_ = false;
  bool reported_ = false;
  bool recovered_ = false;
  double stalled_since_s_ = 0.0;
  double recovery_for_s_ = 0.0;
  std::optional<double> stop_at_s_;
  bool finished_ = false;
  size_t stalls_ = 0;
  double longest_stall_s_ = 0.0;
};

}  // namespace uavsim::server::sim
