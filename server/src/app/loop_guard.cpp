#include "app/loop_guard.hpp"

#include <chrono>
#include <cstdio>
#include <ostream>
#include <sstream>
#include <string>

namespace uavsim::server::app {

namespace {

// how often the watchdog looks: a tenth of a second costs nothing and keeps the grace time exact
constexpr auto kPollPeriod = std::chrono::milliseconds(100);

double wall_s() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

std::string seconds(double s) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.1f s", s);
  return buf;
}

}  // namespace

LoopGuard::LoopGuard(const sim::LoopActivity& activity, sim::WatchdogOptions options,
                     bool report_stalls, std::function<int()> stop_signal, std::ostream& out,
                     std::function<void(int)> exit)
    : watchdog_(activity, options),
      report_stalls_(report_stalls),
      stop_signal_(std::move(stop_signal)),
      out_(out),
      exit_(std::move(exit)) {
  thread_ = std::thread([this] { run(); });
}

LoopGuard::~LoopGuard() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    done_ = true;
  }
  wake_.notify_all();
  thread_.join();
}

void LoopGuard::loop_finished() {
  std::lock_guard<std::mutex> lock(mutex_);
  watchdog_.loop_finished();
}

std::string LoopGuard::summary() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (watchdog_.stalls() == 0) return "no stalls";
  std::ostringstream s;
  s << watchdog_.stalls() << (watchdog_.stalls() == 1 ? " stall" : " stalls") << " (longest "
    << seconds(watchdog_.longest_stall_s()) << ")";
  return s.str();
}

void LoopGuard::run() {
  std::unique_lock<std::mutex> lock(mutex_);
  while (!wake_.wait_for(lock, kPollPeriod, [this] { return done_; })) {
    const double now = wall_s();
    if (const auto stall = watchdog_.poll(now); stall && report_stalls_) {
      out_ << "uavsim-server: watchdog: the simulation loop has made no progress for "
           << seconds(stall->for_s) << " (sim time " << stall->time_s << " s), in "
           << (stall->where.empty() ? "startup" : stall->where) << std::endl;
    }
    if (const auto lasted = watchdog_.take_recovery(); lasted && report_stalls_) {
      out_ << "uavsim-server: watchdog: the simulation loop moves again after " << seconds(*lasted)
           << std::endl;
    }
    const int signal = stop_signal_();
    if (signal == 0) continue;
    watchdog_.stop_requested(now);
    if (watchdog_.must_exit(now)) {
      const sim::LoopActivity& a = watchdog_.activity();
      out_ << "uavsim-server: the simulation loop did not stop within the grace time after signal "
           << signal << " (stuck at sim time " << a.time_s() << " s in " << a.where()
           << "); exiting without it" << std::endl;
      exit_(128 + signal);
      return;
    }
  }
}

}  // namespace uavsim::server::app
