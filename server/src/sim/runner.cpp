#include "sim/runner.hpp"

#include <chrono>
#include <limits>
#include <thread>

namespace uavsim::server::sim {

using SteadyClock = std::chrono::steady_clock;

double SteadyWallClock::now_s() {
  return std::chrono::duration<double>(SteadyClock::now().time_since_epoch()).count();
}

void SteadyWallClock::sleep_until_s(double t_s) {
  const double wait_s = t_s - now_s();
  if (wait_s > 0.0) std::this_thread::sleep_for(std::chrono::duration<double>(wait_s));
}

Runner::Runner(Simulation& sim, double rate_factor, WallClock* clock)
    : sim_(sim), clock_(clock != nullptr ? clock : &steady_clock_), rate_(rate_factor) {}

void Runner::stop() { stop_ = true; }

void Runner::add_gate(Phase phase, std::string name, Gate gate) {
  sim_.schedule().add(phase, std::move(name), [this, gate = std::move(gate)] {
    // the time the gate held the clock (pause, lockstep, requests) is not owed to the simulation
    const double start_s = clock_->now_s();
    gate(sim_.time_s());
    held_s_ += clock_->now_s() - start_s;
  });
}

void Runner::set_rate(double rate_factor) {
  rate_ = rate_factor;
  std::lock_guard<std::mutex> lock(mutex_);
  rebase_ = true;
}

void Runner::run_until(double end_time_s) {
  double wall_anchor_s = clock_->now_s();
  double sim_anchor = sim_.time_s();
  while (!stop_ && sim_.time_s() + 0.5 * sim_.physics_dt_s() < end_time_s) {
    const bool control_next = sim_.step_count() % sim_.control_decimation() == 0;
    held_s_ = 0.0;
    sim_.step();
    wall_anchor_s += held_s_;

    // pacing: at every control step, sleep until wall time catches up with sim time / rate
    const double rate = rate_;
    if (!control_next || rate <= 0.0) continue;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (rebase_) {
        wall_anchor_s = clock_->now_s();
        sim_anchor = sim_.time_s();
        rebase_ = false;
        continue;
      }
    }
    const double due_s = wall_anchor_s + (sim_.time_s() - sim_anchor) / rate;
    if (due_s > clock_->now_s()) clock_->sleep_until_s(due_s);
  }
}

}  // namespace uavsim::server::sim
