#include "fc/pid.hpp"

#include <algorithm>
#include <cmath>

#include "fc/angles.hpp"

namespace uavsim::server::fc {

double Pid::update(double error, double dt_s, const PidGains& gains, bool freeze_i) {
  if (!(dt_s > 0.0)) return last_output_;
  // derivative of the error, low-passed: alpha = dt / (dt + 1/(2 pi fc))
  if (has_last_) {
    const double raw = (error - last_error_) / dt_s;
    const double alpha =
        gains.d_cutoff_hz > 0.0 ? dt_s / (dt_s + 1.0 / (2.0 * kPi * gains.d_cutoff_hz)) : 1.0;
    derivative_ += alpha * (raw - derivative_);
  }
  last_error_ = error;
  has_last_ = true;
  // integrate, unless frozen and growing; clamp to +-imax
  const double delta = gains.i * error * dt_s;
  if (!freeze_i || delta * integrator_ < 0.0) integrator_ += delta;
  integrator_ = std::clamp(integrator_, -gains.imax, gains.imax);
  if (gains.i == 0.0) integrator_ = 0.0;
  last_output_ = gains.p * error + integrator_ + gains.d * derivative_;
  return last_output_;
}

void Pid::reset() {
  integrator_ = 0.0;
  derivative_ = 0.0;
  last_error_ = 0.0;
  last_output_ = 0.0;
  has_last_ = false;
}

}  // namespace uavsim::server::fc
