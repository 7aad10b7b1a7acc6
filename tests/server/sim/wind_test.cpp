// The wind model (airframe/wind.hpp): Dryden-type turbulence statistics, gusts, seeding.
#include "airframe/wind.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace uavsim::server::airframe {
namespace {

constexpr double kExactTol = 1e-12;
// the autocorrelation estimated from one seeded series
constexpr double kCorrTol = 0.05;
// the gust's 1 - cos profile sampled at 1 ms steps
constexpr double kGustTol_m_s = 1e-6;
constexpr double kMeanWindTol_m_s = 1e-9;

WindParams breeze(double sd_m_s) {
  WindParams p;
  p.speed_m_s = 5.0;
  p.from_deg = 90.0;  // from the east: the air moves towards -x
  p.turbulence_sd_m_s = sd_m_s;
  p.length_scale_m = 30.0;  // tau = L / V = 6 s
  return p;
}

TEST(Wind, MeanWindBlowsFromItsDirection) {
  WindField w(breeze(0.0), 1);
  w.step(0.01);
  EXPECT_NEAR(w.velocity_enu_m_s().x(), -5.0, kExactTol);
  EXPECT_NEAR(w.velocity_enu_m_s().y(), 0.0, kExactTol);
  // from the north: towards -y
  EXPECT_NEAR(wind_direction_enu(0.0).y(), -1.0, kExactTol);
}

TEST(Wind, TurbulenceHasTheConfiguredIntensityAndCorrelationTime) {
  // 40000 s with tau = 6 s: about T / (2 tau) = 3300 independent samples, so the sample standard
  // deviation is within sigma / sqrt(2 * 3300) = 1.2 % (1 sd); allow 5 %
  constexpr double kSigma = 1.5;
  constexpr double kDt = 0.05;
  constexpr double kTolerance = 0.05;
  WindField w(breeze(kSigma), 42);
  const double tau_s = 30.0 / 5.0;
  const int lag = static_cast<int>(std::lround(tau_s / kDt));
  double sum2[3] = {0, 0, 0}, sum[3] = {0, 0, 0}, lagged = 0.0;
  std::vector<double> ux;
  const int n = static_cast<int>(40000.0 / kDt);
  ux.reserve(static_cast<size_t>(n));
  for (int k = 0; k < n; ++k) {
    w.step(kDt);
    const Eigen::Vector3d u = w.turbulence_enu_m_s();
    for (int i = 0; i < 3; ++i) {
      sum[i] += u[i];
      sum2[i] += u[i] * u[i];
    }
    ux.push_back(u.x());
    if (k >= lag) lagged += u.x() * ux[static_cast<size_t>(k - lag)];
  }
  auto sd = [&](int i) { return std::sqrt(sum2[i] / n - (sum[i] / n) * (sum[i] / n)); };
  EXPECT_NEAR(sd(0), kSigma, kTolerance * kSigma);
  EXPECT_NEAR(sd(1), kSigma, kTolerance * kSigma);
  EXPECT_NEAR(sd(2), 0.5 * kSigma, kTolerance * kSigma);  // vertical: half, near the ground
  // Gauss-Markov autocorrelation at one correlation time: exp(-1) = 0.37
  const double rho = lagged / (n - lag) / (sum2[0] / n);
  EXPECT_NEAR(rho, std::exp(-1.0), kCorrTol);
}

TEST(Wind, SameSeedSameHistoryDifferentSeedDifferent) {
  WindParams p = breeze(1.0);
  p.gust_rate_hz = 0.1;
  p.gust_m_s = 3.0;
  WindField a(p, 9), b(p, 9), c(p, 10);
  bool differs = false;
  for (int k = 0; k < 20000; ++k) {
    a.step(0.001);
    b.step(0.001);
    c.step(0.001);
    ASSERT_EQ(a.velocity_enu_m_s(), b.velocity_enu_m_s()) << "step " << k;
    differs = differs || a.velocity_enu_m_s() != c.velocity_enu_m_s();
  }
  EXPECT_TRUE(differs);
}

TEST(Wind, GustIsOneMinusCosineAlongTheMeanWind) {
  WindField w(breeze(0.0), 1);
  w.gust(4.0, 2.0);
  // halfway through a 2 s gust: the full 4 m/s on top of the mean 5 m/s, towards -x
  for (int k = 0; k < 1000; ++k) w.step(0.001);
  EXPECT_NEAR(w.velocity_enu_m_s().x(), -9.0, kGustTol_m_s);
  // over: back to the mean
  for (int k = 0; k < 1001; ++k) w.step(0.001);
  EXPECT_NEAR(w.velocity_enu_m_s().x(), -5.0, kMeanWindTol_m_s);
}

TEST(Wind, RandomGustsComeAtTheirRate) {
  WindParams p = breeze(0.0);
  p.gust_rate_hz = 0.05;
  p.gust_m_s = 2.0;
  p.gust_duration_s = 1.0;
  WindField w(p, 3);
  int starts = 0;
  bool in_gust = false;
  for (int k = 0; k < 200000;
       ++k) {  // 2000 s at 10 ms: ~100 gusts (fewer by the time spent in gusts)
    w.step(0.01);
    const bool now = w.gust_m_s() > 0;
    if (now && !in_gust) ++starts;
    in_gust = now;
  }
  EXPECT_GT(starts, 70);
  EXPECT_LT(starts, 130);
}

TEST(Wind, ValidateRejectsNonsense) {
  WindParams p;
  EXPECT_EQ(validate(p), "");
  p.speed_m_s = -1;
  EXPECT_NE(validate(p), "");
  p = {};
  p.length_scale_m = 0;
  EXPECT_NE(validate(p), "");
}

}  // namespace
}  // namespace uavsim::server::airframe
