#include "fc/motor_monitor.hpp"

#include <algorithm>
#include <cmath>

namespace uavsim::server::fc {

namespace {
// residual low-pass: differentiated gyro noise (SIM_GYRO_SD 0.003 rad/s at 500 Hz is ~2 rad/s^2 per
// sample) falls ~7x, while a lost hexa rotor's missing torque (11 N on a 0.45 m arm = 5 N m, i.e.
// ~20 rad/s^2 on J = 0.24 kg m^2) shows within a few tens of milliseconds
constexpr double kResidualTauS = 0.03;
// the residual must point against the candidate's expected torque (cosine) and match its size
constexpr double kMinCosine = 0.9;
constexpr double kMinMissingFraction = 0.5;
constexpr double kMaxMissingFraction = 1.6;
// the accelerometer must also miss at least this fraction of the candidate's thrust
constexpr double kMinThrustDeficitFraction = 0.4;
// only rotors commanded to a real share of the thrust can be judged
constexpr double kMinJudgedThrustFraction = 0.15;
// the same candidate for this long: a real loss persists, a gust or manoeuvre transient does not
constexpr double kConfirmS = 0.12;
}  // namespace

MotorMonitor::MotorMonitor(const airframe::AirframeParams& airframe)
    : n_(std::min(airframe.rotors.size(), kMaxRotors)),
      enabled_(airframe.rotors.size() >= kMinRotors && airframe.rotors.size() <= kMaxRotors),
      mass_kg_(airframe.mass_kg > 0.0 ? airframe.mass_kg : 1.0),
      inertia_(airframe.inertia_body_kgm2) {
  for (std::size_t k = 0; k < n_; ++k) {
    const airframe::RotorParams& r = airframe.rotors[k];
    const Eigen::Vector3d arm = r.position_body_m - airframe.com_body_m;
    // roll/pitch torque per newton of this rotor's thrust, as the mixer's allocation matrix
    arm_roll_[k] = arm.y();
    arm_pitch_[k] = -arm.x();
    max_thrust_n_[k] = r.max_thrust_n;
    time_const_s_[k] = std::max(r.time_const_s, 1e-4);
  }
}

void MotorMonitor::reset() {
  speed_.fill(0.0);
  thrust_lp_n_.fill(0.0);
  have_gyro_ = false;
  residual_lp_nm_.setZero();
  thrust_residual_lp_n_ = 0.0;
  candidate_ = -1;
  candidate_s_ = 0.0;
  lost_ = -1;
}

void MotorMonitor::update(const double* motor_cmd_prev, const Eigen::Vector3d& gyro_body_rad_s,
                          const Eigen::Vector3d& specific_force_body_m_s2, double dt_s,
                          bool airborne) {
  if (!enabled_ || !(dt_s > 0.0)) return;
  // expected rotor speeds over the step just ended (the plant's first-order lag), thrust ~ speed^2;
  // the torque over the step is taken at the mean of the start and end speeds
  if (dt_s != lag_dt_s_) {
    for (std::size_t k = 0; k < n_; ++k) lag_alpha_[k] = 1.0 - std::exp(-dt_s / time_const_s_[k]);
    lag_dt_s_ = dt_s;
  }
  std::array<double, kMaxRotors> thrust{};
  Eigen::Vector2d torque_exp = Eigen::Vector2d::Zero();
  double thrust_exp = 0.0;
  for (std::size_t k = 0; k < n_; ++k) {
    const double start = speed_[k];
    const double cmd = std::clamp(motor_cmd_prev[k], 0.0, 1.0);
    speed_[k] += (cmd - speed_[k]) * lag_alpha_[k];
    const double mid = 0.5 * (start + speed_[k]);
    thrust[k] = max_thrust_n_[k] * mid * mid;
    torque_exp += thrust[k] * Eigen::Vector2d(arm_roll_[k], arm_pitch_[k]);
    thrust_exp += thrust[k];
  }
  const bool had_gyro = have_gyro_;
  const Eigen::Vector3d last = last_gyro_;
  last_gyro_ = gyro_body_rad_s;
  have_gyro_ = true;
  if (lost_ >= 0) return;  // latched until reset (re-arming)
  if (!airborne || !had_gyro) {
    residual_lp_nm_.setZero();
    thrust_residual_lp_n_ = 0.0;
    for (std::size_t k = 0; k < n_; ++k) thrust_lp_n_[k] = thrust[k];
    candidate_ = -1;
    return;
  }
  // measured torque: J alpha + omega x J omega, alpha from the gyro difference
  const Eigen::Vector3d mid_rate = 0.5 * (last + gyro_body_rad_s);
  const Eigen::Vector3d torque_meas =
      inertia_ * ((gyro_body_rad_s - last) / dt_s) + mid_rate.cross(inertia_ * mid_rate);
  const double a = dt_s / (dt_s + kResidualTauS);
  residual_lp_nm_ += a * (torque_meas.head<2>() - torque_exp - residual_lp_nm_);
  // thrust: the accelerometer's body-z specific force (drag is small beside a rotor's share)
  thrust_residual_lp_n_ +=
      a * (mass_kg_ * specific_force_body_m_s2.z() - thrust_exp - thrust_residual_lp_n_);
  for (std::size_t k = 0; k < n_; ++k) thrust_lp_n_[k] += a * (thrust[k] - thrust_lp_n_[k]);

  // the rotor whose missing contribution best explains the residual
  const double r_norm = residual_lp_nm_.norm();
  int best = -1;
  double best_cos = kMinCosine;
  for (std::size_t k = 0; k < n_; ++k) {
    const double t = thrust_lp_n_[k];
    if (t < kMinJudgedThrustFraction * max_thrust_n_[k]) continue;
    const Eigen::Vector2d c = t * Eigen::Vector2d(arm_roll_[k], arm_pitch_[k]);
    const double c2 = c.squaredNorm();
    if (c2 < 1e-12 || r_norm < 1e-12) continue;
    const double cosine = -residual_lp_nm_.dot(c) / (r_norm * std::sqrt(c2));
    const double missing = -residual_lp_nm_.dot(c) / c2;
    const bool thrust_short = thrust_residual_lp_n_ < -kMinThrustDeficitFraction * t;
    if (cosine > best_cos && missing > kMinMissingFraction && missing < kMaxMissingFraction &&
        thrust_short) {
      best_cos = cosine;
      best = static_cast<int>(k);
    }
  }
  if (best >= 0 && best == candidate_) {
    candidate_s_ += dt_s;
    if (candidate_s_ >= kConfirmS) lost_ = best;
  } else {
    candidate_ = best;
    candidate_s_ = best >= 0 ? dt_s : 0.0;
  }
}

}  // namespace uavsim::server::fc
