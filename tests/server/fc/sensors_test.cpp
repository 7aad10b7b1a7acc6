#include "fc/sensors.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "fc/angles.hpp"

namespace uavsim::server::fc {
namespace {

// 20000 samples: the standard error of a measured std is ~0.5 %; allow 5 %
constexpr double kStdRelTol = 0.05;
constexpr int kSamples = 20000;
constexpr double kExactTol = 1e-12;

double stddev(const std::vector<double>& v) {
  double mean = 0.0;
  for (double x : v) mean += x;
  mean /= v.size();
  double var = 0.0;
  for (double x : v) var += (x - mean) * (x - mean);
  return std::sqrt(var / (v.size() - 1));
}

TruthState hover_truth() {
  TruthState t;
  t.position_enu_m = Eigen::Vector3d(1, 2, 10);
  t.on_ground = false;
  return t;
}

TEST(Sensors, SameSeedSameSamplesDifferentSeedDifferent) {
  ParamValues p;
  Sensors a(5), b(5), c(6);
  SensorFrame fa, fb, fc;
  const TruthState t = hover_truth();
  bool differ = false;
  for (int k = 0; k < 1000; ++k) {
    const double time = k * 0.002;
    a.sample(time, t, p, &fa);
    b.sample(time, t, p, &fb);
    c.sample(time, t, p, &fc);
    EXPECT_EQ(fa.imu.gyro_body_rad_s, fb.imu.gyro_body_rad_s);
    EXPECT_EQ(fa.gps.position_enu_m, fb.gps.position_enu_m);
    EXPECT_EQ(fa.baro_alt_m, fb.baro_alt_m);
    differ = differ || fa.imu.gyro_body_rad_s != fc.imu.gyro_body_rad_s;
  }
  EXPECT_TRUE(differ);
}

TEST(Sensors, SampleRatesAreRespected) {
  ParamValues p;  // GPS 10 Hz, baro 50 Hz, control at 500 Hz
  Sensors s(1);
  SensorFrame f;
  int gps = 0, baro = 0;
  for (int k = 0; k < 5000; ++k) {  // 10 s
    s.sample(k * 0.002, hover_truth(), p, &f);
    gps += f.gps_new;
    baro += f.baro_new;
  }
  EXPECT_EQ(gps, 100);
  EXPECT_EQ(baro, 500);
}

TEST(Sensors, NoiseHasConfiguredStandardDeviation) {
  ParamValues p;
  p.sim_gps_hz = 500.0;
  p.sim_baro_hz = 500.0;
  Sensors s(11);
  SensorFrame f;
  const TruthState t = hover_truth();
  std::vector<double> gps_x, gps_z, gps_vx, baro, gyro_x, acc_z;
  for (int k = 0; k < kSamples; ++k) {
    s.sample(k * 0.002, t, p, &f);
    gps_x.push_back(f.gps.position_enu_m.x());
    gps_z.push_back(f.gps.position_enu_m.z());
    gps_vx.push_back(f.gps.velocity_enu_m_s.x());
    baro.push_back(f.baro_alt_m);
    gyro_x.push_back(f.imu.gyro_body_rad_s.x());
    acc_z.push_back(f.imu.accel_body_m_s2.z());
  }
  EXPECT_NEAR(stddev(gps_x), p.sim_gps_pos_h_sd, kStdRelTol * p.sim_gps_pos_h_sd);
  EXPECT_NEAR(stddev(gps_z), p.sim_gps_pos_v_sd, kStdRelTol * p.sim_gps_pos_v_sd);
  EXPECT_NEAR(stddev(gps_vx), p.sim_gps_vel_sd, kStdRelTol * p.sim_gps_vel_sd);
  EXPECT_NEAR(stddev(baro), p.sim_baro_sd, kStdRelTol * p.sim_baro_sd);
  EXPECT_NEAR(stddev(gyro_x), p.sim_gyro_sd, kStdRelTol * p.sim_gyro_sd);
  EXPECT_NEAR(stddev(acc_z), p.sim_accel_sd, kStdRelTol * p.sim_accel_sd);
}

TEST(Sensors, AccelerometerMeasuresSpecificForce) {
  ParamValues p;
  p.sim_accel_sd = 0.0;
  Sensors s(1);
  SensorFrame f;
  TruthState t = hover_truth();
  // rolled 90 degrees about body x: gravity's reaction (up in ENU) appears along body +y... R^T (0,0,g)
  t.q_enu_body = Eigen::Quaterniond(Eigen::AngleAxisd(kPi / 2.0, Eigen::Vector3d::UnitX()));
  t.accel_enu_m_s2 = Eigen::Vector3d(1.0, 0.0, 0.0);
  s.sample(0.0, t, p, &f);
  const Eigen::Vector3d expected =
      t.q_enu_body.toRotationMatrix().transpose() * Eigen::Vector3d(1.0, 0.0, kGravityM_S2);
  EXPECT_LT((f.imu.accel_body_m_s2 - expected).norm(), 1e-12);
}

TEST(Sensors, GpsDenialAndGlitch) {
  ParamValues p;
  p.sim_gps_pos_h_sd = p.sim_gps_pos_v_sd = 0.0;
  Sensors s(1);
  SensorFrame f;
  s.set_gps_denied(true);
  s.sample(0.0, hover_truth(), p, &f);
  EXPECT_TRUE(f.gps_new);
  EXPECT_FALSE(f.gps.fix_3d);
  EXPECT_EQ(f.gps.satellites, 0);
  s.set_gps_denied(false);
  s.set_gps_glitch(Eigen::Vector3d(30, 0, 0));
  s.sample(0.1, hover_truth(), p, &f);
  EXPECT_TRUE(f.gps.fix_3d);
  EXPECT_EQ(f.gps.satellites, 12);
  EXPECT_NEAR(f.gps.position_enu_m.x(), 31.0, kExactTol);
}

}  // namespace
}  // namespace uavsim::server::fc
