#include "fc/pid.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "fc/angles.hpp"

namespace uavsim::server::fc {
namespace {

// a first-order filter stepped at a finite rate, against the continuous response
constexpr double kStepResponseTol = 0.02;

TEST(Pid, IntegratorIsLimitedToImax) {
  Pid pid;
  const PidGains g{0.0, 10.0, 0.0, 2.0, 0.0};
  double out = 0.0;
  for (int k = 0; k < 1000; ++k) out = pid.update(1.0, 0.01, g);
  // unlimited it would be 10 * 1 * 10 s = 100; the limit is 2
  EXPECT_DOUBLE_EQ(out, 2.0);
  for (int k = 0; k < 1000; ++k) out = pid.update(-1.0, 0.01, g);
  EXPECT_DOUBLE_EQ(out, -2.0);
}

TEST(Pid, FrozenIntegratorOnlyShrinks) {
  Pid pid;
  const PidGains g{0.0, 1.0, 0.0, 10.0, 0.0};
  for (int k = 0; k < 100; ++k) pid.update(1.0, 0.01, g);
  const double i0 = pid.integrator();
  pid.update(1.0, 0.01, g, true);
  EXPECT_DOUBLE_EQ(pid.integrator(), i0);
  pid.update(-1.0, 0.01, g, true);
  EXPECT_LT(pid.integrator(), i0);
}

TEST(Pid, DerivativeFilterIsFirstOrderLowPass) {
  // a ramp e = t has de/dt = 1: the filtered derivative approaches 1 with time constant 1/(2 pi fc)
  Pid pid;
  const double fc_hz = 5.0, dt = 0.001;
  const PidGains g{0.0, 0.0, 1.0, 0.0, fc_hz};
  double t = 0.0, out = 0.0;
  pid.update(0.0, dt, g);
  const double tau = 1.0 / (2.0 * kPi * fc_hz);
  for (int k = 0; k < static_cast<int>(tau / dt); ++k) {
    t += dt;
    out = pid.update(t, dt, g);
  }
  // after one time constant: 1 - e^-1 = 0.632
  EXPECT_NEAR(out, 1.0 - std::exp(-1.0), kStepResponseTol);
}

TEST(Pid, DerivativeFilterAttenuatesNoise) {
  // alternating +-1 error at 1 kHz (500 Hz content) through a 20 Hz filter
  Pid filtered, raw;
  const PidGains gf{0.0, 0.0, 1.0, 0.0, 20.0};
  const PidGains gr{0.0, 0.0, 1.0, 0.0, 0.0};
  double max_f = 0.0, max_r = 0.0;
  for (int k = 0; k < 1000; ++k) {
    const double e = (k % 2 == 0) ? 1.0 : -1.0;
    const double f = filtered.update(e, 0.001, gf), r = raw.update(e, 0.001, gr);
    if (k < 500) continue;  // past the start-up transient
    max_f = std::max(max_f, std::abs(f));
    max_r = std::max(max_r, std::abs(r));
  }
  EXPECT_LT(max_f, 0.1 * max_r);
}

TEST(Pid, ZeroDtKeepsLastOutput) {
  Pid pid;
  const PidGains g{2.0, 0.0, 0.0, 0.0, 0.0};
  EXPECT_DOUBLE_EQ(pid.update(1.5, 0.01, g), 3.0);
  EXPECT_DOUBLE_EQ(pid.update(100.0, 0.0, g), 3.0);
}

}  // namespace
}  // namespace uavsim::server::fc
