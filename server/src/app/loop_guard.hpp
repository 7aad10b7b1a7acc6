// The server's watchdog thread (sim/loop_watchdog.hpp decides, this acts): it reports a simulation
// loop that has made no progress for --watchdog seconds, with where the loop is, and reports when
// it moves again; and when a SIGTERM or SIGINT has not ended the loop within the grace time, it
// ends the process itself (exit 128 + the signal), so that a stop request always stops the server.
#pragma once

#include <atomic>
#include <condition_variable>
#include <functional>
#include <iosfwd>
#include <mutex>
#include <thread>

#include "sim/loop_watchdog.hpp"

namespace uavsim::server::app {

class LoopGuard {
 public:
  // stop_signal: 0 while no stop is requested, else the signal that asked (SIGTERM, SIGINT). exit:
  // how the process ends when the loop ignores the stop (std::_Exit in the server; a recorder in
  // tests). Starts the thread.
  LoopGuard(const sim::LoopActivity& activity, sim::WatchdogOptions options, bool report_stalls,
            std::function<int()> stop_signal, std::ostream& out,
            std::function<void(int code)> exit);
  // Stops the thread (after the loop has finished).
  ~LoopGuard();
  LoopGuard(const LoopGuard&) = delete;
  LoopGuard& operator=(const LoopGuard&) = delete;

  // The loop thread has left its loop: stalls no longer count, and the process exits its own way.
  // Thread-safe.
  void loop_finished();
  // "no stalls" or "1 stall (longest 12.0 s)". Thread-safe.
  std::string summary();

 private:
  void run();

  sim::LoopWatchdog watchdog_;
  bool report_stalls_;
  std::function<int()> stop_signal_;
  std::ostream& out_;
  std::function<void(int)> exit_;
  std::mutex mutex_;  // guards watchdog_ and done_
  std::condition_variable wake_;
  bool done_ = false;
  std::thread thread_;
};

}  // namespace uavsim::server::app
