// The estimator: complementary filters in place of ArduPilot's EKF.
//  - attitude: gyro integration corrected by gravity (accelerometer, minus the GPS-derived kinematic
//    acceleration, as ArduPilot's DCM does) and by compass heading (Mahony et al. 2008, passive filter);
//  - position/velocity: accelerometer integration (rotated to ENU, minus gravity) corrected by GPS
//    horizontally and by the barometer vertically, with the third-order complementary filter of
//    ArduPilot's legacy AP_InertialNav (gains 3/tau, 3/tau^2, 1/tau^3 on position error; the third
//    state is an accelerometer bias in ENU).
// No allocation in update().
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "fc/fc_types.hpp"
#include "fc/sensors.hpp"

namespace uavsim::server::fc {

class Estimator {
 public:
  // (sensor frame, time, dt) => updated estimate. dt <= 0 only re-reads the sensors' flags.
  void update(double time_s, double dt_s, const SensorFrame& sensors);

  const EstimatedState& state() const { return state_; }
  bool attitude_ok() const { return attitude_init_; }
  bool position_ok() const { return position_init_; }
  // Attitude and position initialised and settled for kSettleS seconds.
  bool converged(double time_s) const;
  bool gps_glitching() const { return gps_rejecting_; }
  double yaw_enu_rad() const;
  // Vertical acceleration low-passed at ~1 Hz, for the land detector.
  double accel_z_filtered_m_s2() const { return accel_z_lp_m_s2_; }
  // Forgets everything (a reboot).
  void reset() { *this = Estimator(); }

 private:
  void update_attitude(double dt_s, const SensorFrame& sensors);
  void update_position(double time_s, double dt_s, const SensorFrame& sensors);

  EstimatedState state_;
  bool attitude_init_ = false;
  bool position_init_ = false;
  bool baro_init_ = false;
  double position_init_time_s_ = 0.0;
  double attitude_init_time_s_ = 0.0;
  double time_s_ = 0.0;  // of the last update
  double last_gps_time_s_ = -1e9;
  // heading from the latest compass sample, and whether one arrived
  double mag_heading_rad_ = 0.0;
  bool have_mag_ = false;
  // GPS-derived kinematic acceleration for the gravity reference
  Eigen::Vector3d last_gps_vel_enu_m_s_ = Eigen::Vector3d::Zero();
  double last_gps_vel_time_s_ = -1.0;
  Eigen::Vector3d gps_accel_lp_enu_m_s2_ = Eigen::Vector3d::Zero();
  // inertial-nav corrections held between measurements (ArduPilot style): position error to apply
  Eigen::Vector3d pos_error_enu_m_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d accel_bias_enu_m_s2_ = Eigen::Vector3d::Zero();
  double accel_z_lp_m_s2_ = 0.0;
  // glitch handling: GPS fixes rejected since this time
  bool gps_rejecting_ = false;
  double gps_reject_since_s_ = 0.0;
};

}  // namespace uavsim::server::fc
