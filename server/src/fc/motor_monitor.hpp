// Motor-loss detection from the control response, without ground truth (the FC cannot see which
// motor failed). ArduCopter's thrust-boost logic spots a motor held at its command limit; here the
// same loss is found earlier from the torque it leaves missing: the body angular acceleration the
// gyro measures is compared with what the commanded motors should produce (rotor speed through the
// motor lag, thrust ~ speed^2, the allocation matrix, J alpha = tau - omega x J omega). A lost rotor
// leaves a roll/pitch residual equal to minus its own expected torque, and an equal thrust deficit on
// the accelerometer; the rotor whose expected contribution matches both, persistently, is declared
// lost. Only vehicles with at least kMinRotors rotors (as ArduCopter: a quad cannot fly on three).
// No allocation in update().
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstddef>

#include "airframe/airframe.hpp"
#include "fc/mixer.hpp"

namespace uavsim::server::fc {

class MotorMonitor {
 public:
  static constexpr std::size_t kMinRotors = 6;

  explicit MotorMonitor(const airframe::AirframeParams& airframe);

  // (motor commands sent last step and applied since, gyro now, specific force now, dt, airborne)
  // => detection state. airborne: in flight with a collective near hover; otherwise the contact and
  // spin-up transients are not the model's, and the monitor only tracks the motor states.
  void update(const double* motor_cmd_prev, const Eigen::Vector3d& gyro_body_rad_s,
              const Eigen::Vector3d& specific_force_body_m_s2, double dt_s, bool airborne);
  // Forgets a detection and the filters (arming).
  void reset();
  // The lost rotor, or -1.
  int lost_rotor() const { return lost_; }

 private:
  std::size_t n_ = 0;
  bool enabled_ = false;
  double mass_kg_ = 0.0;
  Eigen::Matrix3d inertia_ = Eigen::Matrix3d::Identity();
  std::array<double, kMaxRotors> arm_roll_{}, arm_pitch_{}, max_thrust_n_{}, time_const_s_{};
  // state
  std::array<double, kMaxRotors> speed_{};  // modelled normalised rotor speed
  std::array<double, kMaxRotors> lag_alpha_{};  // 1 - exp(-dt/tau) for lag_dt_s_ (dt rarely changes)
  double lag_dt_s_ = -1.0;
  Eigen::Vector3d last_gyro_ = Eigen::Vector3d::Zero();
  bool have_gyro_ = false;
  Eigen::Vector2d residual_lp_nm_ = Eigen::Vector2d::Zero();  // roll/pitch torque residual
  double thrust_residual_lp_n_ = 0.0;
  std::array<double, kMaxRotors> thrust_lp_n_{};  // expected rotor thrusts, same filter
  int candidate_ = -1;
  double candidate_s_ = 0.0;
  int lost_ = -1;
};

}  // namespace uavsim::server::fc
