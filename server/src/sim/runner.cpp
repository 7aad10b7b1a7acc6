#include "sim/runner.hpp"

#include <chrono>
#include <limits>
#include <thread>

namespace uavsim::server::sim {

using SteadyClock = std::chrono::steady_clock;

Runner::Runner(Simulation& sim, double rate_factor) : sim_(sim), rate_(rate_factor) {}

void Runner::stop() {
  stop_ = true;
  wake_.notify_all();
}

void Runner::set_rate(double rate_factor) {
  rate_ = rate_factor;
  std::lock_guard<std::mutex> lock(mutex_);
  rebase_ = true;
}

void Runner::pause() { paused_ = true; }

void Runner::resume() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    paused_ = false;
    rebase_ = true;
  }
  wake_.notify_all();
}

void Runner::step_while_paused(uint64_t steps) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    steps_allowed_ += steps;
  }
  wake_.notify_all();
}

void Runner::wait_while_paused() {
  std::unique_lock<std::mutex> lock(mutex_);
  wake_.wait(lock, [this] { return !paused_ || steps_allowed_ > 0 || stop_; });
  if (paused_ && steps_allowed_ > 0) --steps_allowed_;
  if (paused_) rebase_ = true;
}

void Runner::run_until(double end_time_s) {
  SteadyClock::time_point wall_anchor = SteadyClock::now();
  double sim_anchor = sim_.time_s();
  while (!stop_ && sim_.time_s() + 0.5 * sim_.physics_dt_s() < end_time_s) {
    if (paused_) wait_while_paused();
    if (stop_) break;

    const bool control_next = sim_.step_count() % sim_.control_decimation() == 0;
    if (control_next && gate_) gate_(sim_.time_s());
    sim_.step();

    // pacing: at every control step, sleep until wall time catches up with sim time / rate
    const double rate = rate_;
    if (!control_next || rate <= 0.0) continue;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (rebase_) {
        wall_anchor = SteadyClock::now();
        sim_anchor = sim_.time_s();
        rebase_ = false;
        continue;
      }
    }
    const auto due = wall_anchor + std::chrono::duration_cast<SteadyClock::duration>(
                                       std::chrono::duration<double>((sim_.time_s() - sim_anchor) / rate));
    if (due > SteadyClock::now()) std::this_thread::sleep_until(due);
  }
}

}  // namespace uavsim::server::sim
