// Seeded sensor models sampled from ground truth: IMU (every control step), GPS, barometer and compass
// at their own rates. All noise comes from one seeded generator (fc/gaussian.hpp: a ziggurat on
// xoshiro256++, several times cheaper than std::normal_distribution and the same sequence with any
// standard library), drawn in a fixed order, so equal seeds and equal truth give equal samples. No
// allocation in sample().
// The field errors (SIM_GPS_BIAS_*, SIM_GPS_JUMP_*, SIM_BARO_DRIFT, SIM_MAG_OFS_SD; all 0 in the ideal
// world) draw from a second generator, so switching them on leaves the white noise sequence unchanged:
//   GPS bias: first-order Gauss-Markov b[k+1] = a b[k] + sd sqrt(1 - a^2) n, a = exp(-T / tau), started in
//     its stationary distribution (horizontal sd SIM_GPS_BIAS_SD, vertical twice); jumps at Poisson times
//     (SIM_GPS_JUMP_HZ) add N(0, SIM_GPS_JUMP_M) per axis to the bias, which then decays back.
//   RTK (SIM_GPS_RTK = 1): 1 cm / 2 cm / 2 cm/s white noise and no bias or jumps (an RTK fixed solution).
//   barometer drift: the same Gauss-Markov process with a 300 s correlation time.
//   compass: a constant heading offset, N(0, SIM_MAG_OFS_SD) drawn once per vehicle.
#pragma once

#include <Eigen/Core>
#include <cstdint>

#include "fc/gaussian.hpp"

#include "fc/fc_types.hpp"
#include "fc/params.hpp"

namespace uavsim::server::fc {

inline constexpr double kGravityM_S2 = 9.80665;

struct ImuSample {
  Eigen::Vector3d gyro_body_rad_s = Eigen::Vector3d::Zero();
  Eigen::Vector3d accel_body_m_s2 = Eigen::Vector3d::Zero();  // specific force R^T (a + g)
};

struct GpsSample {
  Eigen::Vector3d position_enu_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d velocity_enu_m_s = Eigen::Vector3d::Zero();
  bool fix_3d = false;
  int satellites = 0;
  double hdop = 99.99;
};

// What arrived in one sample() call; the flags say which slow sensors produced a new sample.
struct SensorFrame {
  ImuSample imu;
  GpsSample gps;
  double baro_alt_m = 0.0;       // altitude of the ENU origin plane, z up
  double heading_enu_rad = 0.0;  // compass yaw, ENU (0 = east, ccw)
  bool gps_new = false;
  bool baro_new = false;
  bool mag_new = false;
};

class Sensors {
 public:
  explicit Sensors(uint64_t seed);

  // (time, truth) => the samples due at time_s; the IMU is sampled on every call, the others when
  // their period (1 / rate from params) has elapsed since their last sample.
  void sample(double time_s, const TruthState& truth, const ParamValues& params, SensorFrame* out);

  void set_gps_denied(bool denied) { gps_denied_ = denied; }
  void set_gps_glitch(const Eigen::Vector3d& offset_enu_m) { gps_glitch_enu_m_ = offset_enu_m; }
  bool gps_denied() const { return gps_denied_; }
  // The present GPS bias (the field error added to truth, before the glitch offset) and baro drift.
  const Eigen::Vector3d& gps_bias_enu_m() const { return gps_bias_enu_m_; }

 private:
  double gauss(double sd) { return sd > 0.0 ? sd * noise_() : 0.0; }
  static bool due(double time_s, double rate_hz, double* next_s);

  Gaussian noise_;
  double next_gps_s_ = 0.0;
  double next_baro_s_ = 0.0;
  double next_mag_s_ = 0.0;
  bool gps_denied_ = false;
  Eigen::Vector3d gps_glitch_enu_m_ = Eigen::Vector3d::Zero();
  // field errors: their own generator, so the white noise above does not depend on them
  Gaussian errors_;
  Eigen::Vector3d gps_bias_enu_m_ = Eigen::Vector3d::Zero();
  bool gps_bias_started_ = false;
  double baro_drift_m_ = 0.0;
  bool baro_drift_started_ = false;
  double mag_offset_unit_ = 0.0;  // N(0, 1), scaled by SIM_MAG_OFS_SD
};

}  // namespace uavsim::server::fc
