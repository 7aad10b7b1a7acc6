// Field sensor errors (fc/sensors.hpp): the GPS's wandering bias and jumps, RTK, barometer drift
// and the compass offset, sampled from a vehicle at rest.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "fc/sensors.hpp"

namespace uavsim::server::fc {
namespace {

// the measured deviations of correlated errors: few independent samples
constexpr double kGpsBiasStdRelTol = 0.15;
constexpr double kRtkHStdTolM = 0.001;
constexpr double kRtkVStdTolM = 0.002;
constexpr double kBaroStdRelTol = 0.2;  // N_eff ~ 150
// five deviations of the compass offset (SIM_MAG_OFS_SD 0.05 rad) bound a single draw
constexpr double kMagOffsetMaxRad = 5 * 0.05;

TruthState at_rest() {
  TruthState t;
  t.position_enu_m = Eigen::Vector3d(1, 2, 10);
  t.on_ground = false;
  return t;
}

double stddev(const std::vector<double>& v) {
  double mean = 0.0;
  for (double x : v) mean += x;
  mean /= static_cast<double>(v.size());
  double var = 0.0;
  for (double x : v) var += (x - mean) * (x - mean);
  return std::sqrt(var / static_cast<double>(v.size() - 1));
}

// every GPS sample of `seconds` of sensor time at 10 Hz (the GPS rate), minus truth
std::vector<Eigen::Vector3d> gps_errors(const ParamValues& p, double seconds, uint64_t seed = 3) {
  Sensors s(seed);
  SensorFrame f;
  const TruthState t = at_rest();
  std::vector<Eigen::Vector3d> out;
  const int n = static_cast<int>(seconds * p.sim_gps_hz);
  for (int k = 0; k < n; ++k) {
    s.sample(k / p.sim_gps_hz, t, p, &f);
    if (f.gps_new) out.push_back(f.gps.position_enu_m - t.position_enu_m);
  }
  return out;
}

TEST(SensorErrors, GpsBiasWandersWithItsStationaryDeviation) {
  // bias alone: 0.7 m sd, tau 120 s; over 400 tau (N_eff ~ 200) the sample sd is within ~5 % (1
  // sd): allow 15 %
  ParamValues p;
  p.sim_gps_pos_h_sd = 0.0;
  p.sim_gps_pos_v_sd = 0.0;
  p.sim_gps_bias_sd = 0.7;
  p.sim_gps_bias_tau = 120.0;
  const auto e = gps_errors(p, 400 * 120.0);
  std::vector<double> x, z;
  double lag1 = 0.0, sum2 = 0.0;
  for (size_t k = 0; k < e.size(); ++k) {
    x.push_back(e[k].x());
    z.push_back(e[k].z());
    if (k > 0) lag1 += e[k].x() * e[k - 1].x();
    sum2 += e[k].x() * e[k].x();
  }
  EXPECT_NEAR(stddev(x), 0.7, kGpsBiasStdRelTol * 0.7);
  EXPECT_NEAR(stddev(z), 1.4, kGpsBiasStdRelTol * 1.4);  // vertical: twice
  // slowly: one 0.1 s sample to the next is correlated by exp(-0.1 / 120)
  EXPECT_GT(lag1 / sum2, 0.99);
}

TEST(SensorErrors, GpsJumpsComeAtTheirRateAndDecay) {
  // jumps alone: 0.01 Hz for 10000 s = ~100 jumps of 1.5 m sd per axis, decaying in between
  ParamValues p;
  p.sim_gps_pos_h_sd = 0.0;
  p.sim_gps_pos_v_sd = 0.0;
  p.sim_gps_jump_hz = 0.01;
  p.sim_gps_jump_m = 1.5;
  p.sim_gps_bias_tau = 30.0;
  const auto e = gps_errors(p, 10000.0);
  int jumps = 0;
  for (size_t k = 1; k < e.size(); ++k) {
    // a decay step is at most |b| * (1 - exp(-0.1 / 30)) = a few mm; a jump is tens of cm or more
    if ((e[k] - e[k - 1]).head<2>().norm() > 0.1) ++jumps;
  }
  EXPECT_GT(jumps, 70);
  EXPECT_LT(jumps, 130);
}

TEST(SensorErrors, RtkIsCentimetreLevelWithoutBias) {
  ParamValues p;
  p.sim_gps_bias_sd = 0.7;  // ignored in RTK
  p.sim_gps_jump_hz = 0.1;
  p.sim_gps_rtk = 1.0;
  const auto e = gps_errors(p, 2000.0);
  std::vector<double> x, z;
  for (const auto& v : e) {
    x.push_back(v.x());
    z.push_back(v.z());
  }
  EXPECT_NEAR(stddev(x), 0.01, kRtkHStdTolM);
  EXPECT_NEAR(stddev(z), 0.02, kRtkVStdTolM);
  double max_h = 0.0;
  for (const auto& v : e) max_h = std::max(max_h, v.head<2>().norm());
  EXPECT_LT(max_h, 0.08);  // no jumps: 1 cm noise, 20000 samples stay within ~5 sd
}

TEST(SensorErrors, FieldErrorsLeaveTheWhiteNoiseSequenceAlone) {
  // the errors draw from their own generator: with them on, a sample is the ideal one + the bias
  ParamValues ideal, field;
  field.sim_gps_bias_sd = 0.7;
  field.sim_gps_jump_hz = 0.01;
  field.sim_gps_jump_m = 1.5;
  Sensors a(11), b(11);
  SensorFrame fa, fb;
  const TruthState t = at_rest();
  for (int k = 0; k < 5000; ++k) {
    a.sample(k * 0.002, t, ideal, &fa);
    b.sample(k * 0.002, t, field, &fb);
    ASSERT_EQ(fa.imu.gyro_body_rad_s, fb.imu.gyro_body_rad_s);
    if (fa.gps_new) {
      ASSERT_TRUE(fb.gps_new);
      EXPECT_LT((fb.gps.position_enu_m - fa.gps.position_enu_m - b.gps_bias_enu_m()).norm(), 1e-12);
    }
  }
}

TEST(SensorErrors, BarometerDriftsAndCompassHasAFixedOffset) {
  ParamValues p;
  p.sim_baro_sd = 0.0;
  p.sim_mag_sd = 0.0;
  p.sim_baro_drift = 0.5;
  p.sim_mag_ofs_sd = 0.05;
  Sensors s(21);
  SensorFrame f;
  const TruthState t = at_rest();
  std::vector<double> baro;
  double heading = std::nan("");
  // 300 correlation times of 300 s at the 50 Hz baro rate, sampled at 1 Hz: N_eff ~ 150: 20 %
  for (int k = 0; k < 90000 * 50; k += 1) {
    s.sample(k / 50.0, t, p, &f);
    if (f.baro_new && k % 50 == 0) baro.push_back(f.baro_alt_m - t.position_enu_m.z());
    if (f.mag_new) {
      if (std::isnan(heading)) heading = f.heading_enu_rad;
      ASSERT_EQ(f.heading_enu_rad, heading);  // constant: an offset, not noise
    }
  }
  EXPECT_NEAR(stddev(baro), 0.5, kBaroStdRelTol * 0.5);
  EXPECT_NE(heading, 0.0);
  EXPECT_LT(std::abs(heading), kMagOffsetMaxRad);
}

}  // namespace
}  // namespace uavsim::server::fc
