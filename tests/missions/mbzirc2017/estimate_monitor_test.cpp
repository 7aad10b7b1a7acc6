// The step monitor of the FC's own position estimate (estimate_monitor.hpp) against hand-made
// telemetry: smooth flight with jitter is never a step; a step of the position the velocity does
// not account for is, for settle_s after the sum falls back under the threshold.
#include "estimate_monitor.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

namespace uavsim::missions::mbzirc2017 {
namespace {

constexpr double kTelemetry_s = 0.05;  // 20 Hz LOCAL_POSITION_NED
constexpr double kStepTol_m = 1e-9;

// Flying a curve at 4 m/s, turning at 0.5 rad/s (2 m/s^2 of centripetal acceleration), the
// position jittering by 3 cm (the FC's own GPS corrections): the unexplained sum stays far below
// the 0.6 m threshold (the trapezoid's error on the curve is v w dt^2 / 2 = 2.5 mm a sample).
TEST(EstimateMonitor, SmoothFlightWithJitterIsNeverAStep) {
  EstimateMonitor m;
  std::mt19937 rng(7);
  std::normal_distribution<double> jitter(0.0, 0.03);
  for (int i = 0; i < 2000; ++i) {
    const double t = i * kTelemetry_s, a = 0.5 * t;
    const Eigen::Vector2d p = 8.0 * Eigen::Vector2d(std::sin(a), 1.0 - std::cos(a)) +
                              Eigen::Vector2d(jitter(rng), jitter(rng));
    const Eigen::Vector2d v = 4.0 * Eigen::Vector2d(std::cos(a), std::sin(a));
    m.add(t, p, v);
    ASSERT_FALSE(m.settling()) << "t = " << t << " s, unexplained " << m.unexplained_m() << " m";
  }
  EXPECT_EQ(m.jumps(), 0);
  EXPECT_LT(m.unexplained_m(), 0.3);
}

// Hovering, then the position moves 1.0 m in one sample with no velocity: 1.0 m unexplained, a
// step; it stays in the window for 0.5 s (window_s), then 2.5 s (settle_s) of quiet end it.
TEST(EstimateMonitor, AStepIsNoticedAtOnceAndSettlesAfterItsQuietTime) {
  const EstimateMonitorParams params;
  EstimateMonitor m(params);
  double t = 0.0;
  Eigen::Vector2d p(3.0, -2.0);
  for (; t < 1.0; t += kTelemetry_s) m.add(t, p, Eigen::Vector2d::Zero());
  EXPECT_FALSE(m.settling());
  p += Eigen::Vector2d(0.6, 0.8);  // |step| = 1.0 m
  m.add(t, p, Eigen::Vector2d::Zero());
  EXPECT_TRUE(m.settling());
  EXPECT_NEAR(m.unexplained_m(), 1.0, kStepTol_m);
  EXPECT_EQ(m.jumps(), 1);
  const double stepped_s = t;
  // still settling until the step left the window and settle_s passed after that
  for (t += kTelemetry_s; t < stepped_s + params.window_s + params.settle_s - 0.1;
       t += kTelemetry_s) {
    m.add(t, p, Eigen::Vector2d::Zero());
    ASSERT_TRUE(m.settling()) << t;
  }
  for (; t < stepped_s + params.window_s + params.settle_s + 0.2; t += kTelemetry_s) {
    m.add(t, p, Eigen::Vector2d::Zero());
  }
  EXPECT_FALSE(m.settling());
  EXPECT_EQ(m.jumps(), 1);
}

// The step blended in as the FC does (a third-order complementary filter with a 1.5 s time
// constant, server/src/fc/estimator.hpp) while flying at the truck's speed: a 1.5 m GPS jump is
// noticed about 0.3 s later (3/tc = 2 /s of the error e goes straight into the position, and e
// falls as it does, roughly e(t) = 1.5 m exp(-2t): the sum reaches 0.6 m between 0.25 and 0.3 s).
TEST(EstimateMonitor, AGpsJumpBlendedInByTheFcIsNoticedWithinAThirdOfASecond) {
  EstimateMonitor m;
  const double tc = 1.5, k1 = 3.0 / tc, k2 = 3.0 / (tc * tc), k3 = 1.0 / (tc * tc * tc);
  const double dt = 0.0025;  // the FC's 400 Hz
  const Eigen::Vector2d v_true(1.47, 0.0);
  Eigen::Vector2d p_true(0, 0), p_est(0, 0), v_est = v_true, bias(0, 0);
  double noticed_s = -1.0;
  for (int i = 1; i <= 2000; ++i) {
    const double t = i * dt;
    p_true += v_true * dt;
    const Eigen::Vector2d gps =
        p_true + (t >= 2.0 ? Eigen::Vector2d(-1.5, 0.0) : Eigen::Vector2d(0, 0));
    const Eigen::Vector2d e = gps - p_est;
    v_est += bias * dt + k2 * e * dt;
    p_est += v_est * dt + k1 * e * dt;
    bias += k3 * e * dt;
    if (i % 20 == 0) {  // telemetry at 20 Hz
      m.add(t, p_est, v_est);
      if (t < 2.0) ASSERT_FALSE(m.settling()) << t;
      if (noticed_s < 0.0 && m.settling()) noticed_s = t;
    }
  }
  ASSERT_GE(noticed_s, 2.0);
  EXPECT_LE(noticed_s, 2.35);
  EXPECT_EQ(m.jumps(), 1);
}

// Out of order, repeated and non-finite samples are dropped; a telemetry gap starts the window
// anew (a vehicle that moved during a gap did not step).
TEST(EstimateMonitor, DropsBadSamplesAndStartsAnewAfterAGap) {
  EstimateMonitor m;
  m.add(1.0, Eigen::Vector2d(0, 0), Eigen::Vector2d(0, 0));
  m.add(1.0, Eigen::Vector2d(5, 0), Eigen::Vector2d(0, 0));  // same time: dropped
  m.add(0.9, Eigen::Vector2d(5, 0), Eigen::Vector2d(0, 0));  // older: dropped
  m.add(std::numeric_limits<double>::quiet_NaN(), Eigen::Vector2d(5, 0), Eigen::Vector2d(0, 0));
  m.add(1.05, Eigen::Vector2d(std::numeric_limits<double>::infinity(), 0), Eigen::Vector2d(0, 0));
  m.add(1.05, Eigen::Vector2d(0, 0), Eigen::Vector2d(0, 0));
  EXPECT_FALSE(m.settling());
  EXPECT_DOUBLE_EQ(m.unexplained_m(), 0.0);
  m.add(2.05, Eigen::Vector2d(3, 0), Eigen::Vector2d(0, 0));  // 1 s gap (max_gap_s 0.5)
  EXPECT_FALSE(m.settling());
  EXPECT_EQ(m.jumps(), 0);
}

}  // namespace
}  // namespace uavsim::missions::mbzirc2017
