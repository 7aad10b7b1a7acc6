#include "uavsim/client/pid.hpp"

#include <algorithm>
#include <cmath>

namespace uavsim::client {

Pid::Pid(const PidGains& gains) : gains_(gains) {}

void Pid::set_gains(const PidGains& gains) {
  std::lock_guard lock(mutex_);
  gains_ = gains;
}

PidGains Pid::gains() const {
  std::lock_guard lock(mutex_);
  return gains_;
}

void Pid::reset() {
  integral_ = 0.0;
  d_filtered_ = 0.0;
  has_prev_ = false;
  p_ = i_ = d_ = out_ = 0.0;
}

double Pid::update(double setpoint, double measurement, double dt_s) {
  const PidGains g = gains();
  const double error = setpoint - measurement;
  p_ = g.kp * error;
  if (dt_s > 0.0 && std::isfinite(dt_s)) {
    if (has_prev_) {
      const double raw = -(measurement - prev_measurement_) / dt_s;
      const double alpha = g.derivative_filter_s > 0.0 ? dt_s / (g.derivative_filter_s + dt_s) : 1.0;
      d_filtered_ += alpha * (raw - d_filtered_);
    }
    prev_measurement_ = measurement;
    has_prev_ = true;
    d_ = g.kd * d_filtered_;
    // anti-windup: integrate only while the output is not pushed further into saturation
    const double candidate = integral_ + error * dt_s;
    const double unsat = p_ + g.ki * candidate + d_;
    const bool pushing_high = unsat > g.output_max && error > 0.0;
    const bool pushing_low = unsat < g.output_min && error < 0.0;
    if (!pushing_high && !pushing_low) integral_ = candidate;
    if (g.ki != 0.0 && std::isfinite(g.integral_limit)) {
      const double lim = std::abs(g.integral_limit / g.ki);
      integral_ = std::clamp(integral_, -lim, lim);
    }
  }
  i_ = g.ki * integral_;
  out_ = std::clamp(p_ + i_ + d_, g.output_min, g.output_max);
  return out_;
}

}  // namespace uavsim::client
