// A scalar PID with an integrator limit and a first-order low-pass on the derivative, in the form
// ArduPilot's AC_PID uses: out = P*e + I*integral(e) + D*lowpass(de/dt). Gains are passed per call so a
// parameter change takes effect at the next step without copying.
#pragma once

namespace uavsim::server::fc {

struct PidGains {
  double p = 0.0;
  double i = 0.0;
  double d = 0.0;
  double imax = 0.0;          // |I term| limit, in output units
  double d_cutoff_hz = 0.0;   // derivative low-pass corner; <= 0: unfiltered
};

class Pid {
 public:
  // (error, dt) => output; dt <= 0 returns the last output. freeze_i stops the integrator from growing
  // in magnitude (anti-windup while the output saturates) but still lets it shrink.
  double update(double error, double dt_s, const PidGains& gains, bool freeze_i = false);
  void reset();
  void reset_i() { integrator_ = 0.0; }
  void scale_i(double factor) { integrator_ *= factor; }
  double integrator() const { return integrator_; }
  double derivative() const { return derivative_; }

 private:
  double integrator_ = 0.0;  // already multiplied by I, in output units (ArduPilot convention)
  double derivative_ = 0.0;  // filtered de/dt
  double last_error_ = 0.0;
  double last_output_ = 0.0;
  bool has_last_ = false;
};

}  // namespace uavsim::server::fc
