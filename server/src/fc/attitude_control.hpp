// Attitude controller (ArduCopter AC_AttitudeControl-like): thrust vector + yaw -> attitude target
// (lean limited to ANGLE_MAX) -> quaternion-error P -> body-rate target -> rate PID -> body torque.
// The rate loop works in angular acceleration and multiplies by the inertia, so its gains are
// vehicle-size independent: torque = J (PID(rate error)) + omega x J omega.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "fc/params.hpp"
#include "fc/pid.hpp"

namespace uavsim::server::fc {

// The attitude whose body z is along thrust_enu (tilt limited to max_tilt_rad) and whose heading is
// yaw_enu_rad; a thrust vector pointing down or zero gives a level attitude.
Eigen::Quaterniond attitude_from_thrust(const Eigen::Vector3d& thrust_enu, double yaw_enu_rad,
                                        double max_tilt_rad);

struct RateLimits {
  bool roll_pitch = false;  // the mixer scaled roll/pitch torque down
  bool yaw = false;         // the mixer scaled yaw torque down
};

class AttitudeController {
 public:
  // (attitude target, yaw-rate feed-forward, estimate) => body torque in N m.
  Eigen::Vector3d update(const Eigen::Quaterniond& q_target_enu_body, double yaw_rate_ff_enu_rad_s,
                         const Eigen::Quaterniond& q_est_enu_body,
                         const Eigen::Vector3d& rate_body_rad_s, const Eigen::Matrix3d& inertia,
                         const ParamValues& p, const DerivedParams& d, double dt_s,
                         const RateLimits& limits);
  // (body-rate target) => body torque; the inner loop alone (ATTITUDE_TARGET with body rates).
  Eigen::Vector3d update_rate(const Eigen::Vector3d& rate_target_body_rad_s,
                              const Eigen::Vector3d& rate_body_rad_s,
                              const Eigen::Matrix3d& inertia, const ParamValues& p, double dt_s,
                              const RateLimits& limits);
  void reset();
  // Bleeds the rate integrators toward zero (time constant tau_s), as ArduCopter relaxes them when
  // the land detector suspects ground contact: on the ground they only wind up against the contact.
  void relax_i(double dt_s, double tau_s);
  // Zeroes the rate integrators (the mixer changed under them, e.g. a lost rotor).
  void reset_integrators();
  const Eigen::Vector3d& rate_target() const { return rate_target_body_rad_s_; }

 private:
  Pid roll_, pitch_, yaw_;
  Eigen::Vector3d rate_target_body_rad_s_ = Eigen::Vector3d::Zero();
};

}  // namespace uavsim::server::fc
