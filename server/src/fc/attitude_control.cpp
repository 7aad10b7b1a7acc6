#include "fc/attitude_control.hpp"

#include <algorithm>
#include <cmath>

namespace uavsim::server::fc {

Eigen::Quaterniond attitude_from_thrust(const Eigen::Vector3d& thrust_enu, double yaw_enu_rad,
                                        double max_tilt_rad) {
  // body z along the thrust, tilted at most max_tilt from vertical
  Eigen::Vector3d z_b = Eigen::Vector3d::UnitZ();
  if (thrust_enu.z() > 1e-9) {
    z_b = thrust_enu.normalized();
    const double horiz = z_b.head<2>().norm();
    const double tilt = std::atan2(horiz, z_b.z());
    if (tilt > max_tilt_rad && horiz > 1e-12) {
      const Eigen::Vector2d dir = z_b.head<2>() / horiz;
      z_b << dir * std::sin(max_tilt_rad), std::cos(max_tilt_rad);
    }
  }
  // heading: body x as close as possible to the yaw direction, orthogonal to z_b
  const Eigen::Vector3d x_c(std::cos(yaw_enu_rad), std::sin(yaw_enu_rad), 0.0);
  const Eigen::Vector3d y_b = z_b.cross(x_c).normalized();
  const Eigen::Vector3d x_b = y_b.cross(z_b);
  Eigen::Matrix3d R;
  R.col(0) = x_b;
  R.col(1) = y_b;
  R.col(2) = z_b;
  return Eigen::Quaterniond(R).normalized();
}

void AttitudeController::relax_i(double dt_s, double tau_s) {
  const double f = tau_s / (tau_s + dt_s);
  roll_.scale_i(f);
  pitch_.scale_i(f);
  yaw_.scale_i(f);
}

void AttitudeController::reset_integrators() {
  roll_.reset_i();
  pitch_.reset_i();
  yaw_.reset_i();
}

void AttitudeController::reset() {
  roll_.reset();
  pitch_.reset();
  yaw_.reset();
  rate_target_body_rad_s_.setZero();
}

Eigen::Vector3d AttitudeController::update(const Eigen::Quaterniond& q_target_enu_body,
                                           double yaw_rate_ff_enu_rad_s,
                                           const Eigen::Quaterniond& q_est_enu_body,
                                           const Eigen::Vector3d& rate_body_rad_s,
                                           const Eigen::Matrix3d& inertia, const ParamValues& p,
                                           const DerivedParams& d, double dt_s,
                                           const RateLimits& limits) {
  // attitude error in the body frame, shortest way round: q_err = q_est^-1 q_target
  Eigen::Quaterniond q_err = q_est_enu_body.conjugate() * q_target_enu_body;
  if (q_err.w() < 0.0) q_err.coeffs() = -q_err.coeffs();
  const Eigen::AngleAxisd aa(q_err);
  const Eigen::Vector3d rot_body = aa.angle() * aa.axis();
  // P per axis, plus the yaw-rate feed-forward rotated into the body frame
  Eigen::Vector3d rate_t(p.atc_ang_rll_p * rot_body.x(), p.atc_ang_pit_p * rot_body.y(),
                         p.atc_ang_yaw_p * rot_body.z());
  rate_t += q_est_enu_body.conjugate() * Eigen::Vector3d(0.0, 0.0, yaw_rate_ff_enu_rad_s);
  rate_t.x() = std::clamp(rate_t.x(), -d.rate_rp_max_rad_s, d.rate_rp_max_rad_s);
  rate_t.y() = std::clamp(rate_t.y(), -d.rate_rp_max_rad_s, d.rate_rp_max_rad_s);
  rate_t.z() = std::clamp(rate_t.z(), -d.rate_y_max_rad_s, d.rate_y_max_rad_s);
  return update_rate(rate_t, rate_body_rad_s, inertia, p, dt_s, limits);
}

Eigen::Vector3d AttitudeController::update_rate(const Eigen::Vector3d& rate_target_body_rad_s,
                                                const Eigen::Vector3d& rate_body_rad_s,
                                                const Eigen::Matrix3d& inertia,
                                                const ParamValues& p, double dt_s,
                                                const RateLimits& limits) {
  rate_target_body_rad_s_ = rate_target_body_rad_s;
  const Eigen::Vector3d err = rate_target_body_rad_s - rate_body_rad_s;
  const PidGains gr{p.atc_rat_rll_p, p.atc_rat_rll_i, p.atc_rat_rll_d, p.atc_rat_rll_imax,
                    p.atc_rat_rll_fltd};
  const PidGains gp{p.atc_rat_pit_p, p.atc_rat_pit_i, p.atc_rat_pit_d, p.atc_rat_pit_imax,
                    p.atc_rat_pit_fltd};
  const PidGains gy{p.atc_rat_yaw_p, p.atc_rat_yaw_i, 0.0, p.atc_rat_yaw_imax, 0.0};
  // angular acceleration demand, then torque = J alpha + omega x J omega (gyroscopic compensation)
  const Eigen::Vector3d alpha(roll_.update(err.x(), dt_s, gr, limits.roll_pitch),
                              pitch_.update(err.y(), dt_s, gp, limits.roll_pitch),
                              yaw_.update(err.z(), dt_s, gy, limits.yaw));
  return inertia * alpha + rate_body_rad_s.cross(inertia * rate_body_rad_s);
}

}  // namespace uavsim::server::fc
