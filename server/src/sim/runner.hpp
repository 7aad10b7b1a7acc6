// Drives a Simulation's clock on the calling thread (the loop thread): real time x factor, or as fast as
// possible. Gates (add_gate) are the one place the clock is held: the sim API's pause, resume,
// single-stepping and lockstep contract all act in its gate (api::ApiServer::gate()), registered in the
// schedule's queued-tasks phase.
// Wall-clock time is read here and nowhere in physics or fc.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <mutex>
#include <string>

#include "sim/simulation.hpp"

namespace uavsim::server::sim {

// The wall clock the runner paces against: the steady clock in the server, a fake one in tests.
class WallClock {
 public:
  virtual ~WallClock() = default;
  virtual double now_s() = 0;                // monotonic seconds from an arbitrary origin
  virtual void sleep_until_s(double t_s) = 0;
};

// std::chrono::steady_clock.
class SteadyWallClock : public WallClock {
 public:
  double now_s() override;
  void sleep_until_s(double t_s) override;
};

class Runner {
 public:
  // rate_factor: 1 = real time, 10 = ten times faster, 0 = as fast as possible. clock: null = the steady
  // clock; otherwise it must outlive the runner.
  Runner(Simulation& sim, double rate_factor, WallClock* clock = nullptr);

  // Runs until sim time reaches end_time_s (infinity: until stop()). Loop thread only.
  void run_until(double end_time_s);

  void stop();                             // Thread-safe: run_until returns at the next step.
  void set_rate(double rate_factor);       // Thread-safe.
  double rate() const { return rate_.load(); }

  // Registers gate in the simulation's schedule (sim/step_schedule.hpp) under name, in phase (a control
  // phase: kCapture for camera snapshots, kQueuedTasks for the sim API); it is called on the loop thread
  // with the sim time of the step. The lockstep contract blocks in it until every joined client is
  // done, and the API's pause holds the clock in it. Wall time spent in a gate is time the clock was
  // held: pacing re-anchors after it, so the simulation never fast-forwards to "catch up" after a pause
  // or a slow lockstep client. The runner must outlive the stepping. Before run_until.
  using Gate = std::function<void(double time_s)>;
  void add_gate(Phase phase, std::string name, Gate gate);

 private:
  Simulation& sim_;
  SteadyWallClock steady_clock_;
  WallClock* clock_;
  std::atomic<double> rate_;
  std::atomic<bool> stop_{false};
  std::mutex mutex_;  // guards rebase_
  double held_s_ = 0.0;  // wall time spent in gates during the present step (loop thread)
  bool rebase_ = true;  // re-anchor wall time after a rate change
};

}  // namespace uavsim::server::sim
