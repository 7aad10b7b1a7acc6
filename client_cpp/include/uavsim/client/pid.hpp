// A PID controller for mission-level loops (visual servoing, following, landing on a target) whose gains
// can be changed while it runs (seed 6.1 "PID Tuning": a tuning process or another thread alters them
// live). update() is for the control thread; set_gains()/gains() are thread-safe.
#pragma once

#include <limits>
#include <mutex>

namespace uavsim::client {

struct PidGains {
  double kp = 0.0;
  double ki = 0.0;
  double kd = 0.0;
  double output_min = -std::numeric_limits<double>::infinity();
  double output_max = std::numeric_limits<double>::infinity();
  double integral_limit = std::numeric_limits<double>::infinity();  // |ki * integral| never exceeds this
  double derivative_filter_s = 0.0;  // first-order low-pass time constant on the derivative; 0 = none
};

class Pid {
 public:
  explicit Pid(const PidGains& gains = {});

  // One step: error = setpoint - measurement over dt_s seconds (dt_s <= 0: the derivative and integral are
  // not updated). The derivative acts on the measurement (no kick on setpoint changes); the integral stops
  // growing while the output saturates (anti-windup).
  double update(double setpoint, double measurement, double dt_s);
  // Forgets integral and derivative history.
  void reset();

  void set_gains(const PidGains& gains);  // thread-safe; takes effect at the next update()
  PidGains gains() const;                 // thread-safe

  // Last terms (diagnostics, as the seed's tuning monitor shows them).
  double p_term() const { return p_; }
  double i_term() const { return i_; }
  double d_term() const { return d_; }
  double last_output() const { return out_; }

 private:
  mutable std::mutex mutex_;
  PidGains gains_;
  double integral_ = 0.0;
  double prev_measurement_ = 0.0;
  double d_filtered_ = 0.0;
  bool has_prev_ = false;
  double p_ = 0.0, i_ = 0.0, d_ = 0.0, out_ = 0.0;
};

}  // namespace uavsim::client
