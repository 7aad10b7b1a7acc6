// Position controller (ArduCopter AC_PosControl-like, seed fig. 4.4): position error -> sqrt controller
// -> velocity target (+ feed-forward) -> velocity PID -> acceleration (+ feed-forward); vertically
// acceleration -> PID on the acceleration error -> thrust. Output: the thrust vector in ENU newtons.
#pragma once

#include <Eigen/Core>

#include "fc/fc_types.hpp"
#include "fc/params.hpp"
#include "fc/pid.hpp"

namespace uavsim::server::fc {

// What the modes ask of the position controller. Without use_pos_* the velocity feed-forward is the
// velocity target; without use_vel_xy the horizontal acceleration feed-forward is used as is (ALT_HOLD).
struct PositionSetpoint {
  Eigen::Vector3d position_enu_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d velocity_enu_m_s = Eigen::Vector3d::Zero();   // feed-forward
  Eigen::Vector3d accel_enu_m_s2 = Eigen::Vector3d::Zero();     // feed-forward
  bool use_pos_xy = true;
  bool use_pos_z = true;
  bool use_vel_xy = true;
};

struct ThrustLimits {
  bool thrust_up = false;    // the mixer could not give more thrust
  bool thrust_down = false;  // the mixer could not give less
};

// ArduPilot's sqrt controller: linear (k * error) near zero, then the velocity that stops in `error`
// at constant deceleration accel_max; returns the target rate.
double sqrt_controller(double error, double k, double accel_max, double dt_s);

class PositionController {
 public:
  // (estimate, setpoint) => thrust vector in ENU newtons, for a vehicle of mass_kg.
  Eigen::Vector3d update(const EstimatedState& est, double accel_z_est_m_s2,
                         const PositionSetpoint& sp, const ParamValues& p, const DerivedParams& d,
                         double mass_kg, double dt_s, const ThrustLimits& limits);
  // Clears the integrators, e.g. while sitting on the ground.
  void reset();
  // Presets the vertical integrator (e.g. to fly away from a known thrust).
  const Eigen::Vector3d& velocity_target() const { return vel_target_enu_m_s_; }
  const Eigen::Vector3d& accel_target() const { return accel_target_enu_m_s2_; }

 private:
  Pid vel_x_, vel_y_, acc_z_;
  double acc_err_z_filt_ = 0.0;
  Eigen::Vector3d vel_target_enu_m_s_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d accel_target_enu_m_s2_ = Eigen::Vector3d::Zero();
};

}  // namespace uavsim::server::fc
