#include "fc/position_control.hpp"

#include <algorithm>
#include <cmath>

#include "fc/angles.hpp"
#include "fc/sensors.hpp"

namespace uavsim::server::fc {

namespace {
constexpr double kAccErrCutoffHz = 20.0;  // ArduPilot PSC_ACCZ_FLTE default
constexpr double kVelDCutoffHz = 5.0;     // ArduPilot PSC_VELXY_FLTD default
}  // namespace

double sqrt_controller(double error, double k, double accel_max, double dt_s) {
  if (!(accel_max > 0.0)) return k * error;
  if (!(k > 0.0)) return std::copysign(std::sqrt(2.0 * accel_max * std::abs(error)), error);
  // switch from linear to sqrt where both have the same slope: |e| = accel / k^2
  const double linear_dist = accel_max / (k * k);
  double out;
  if (std::abs(error) > linear_dist) {
    out = std::copysign(std::sqrt(2.0 * accel_max * (std::abs(error) - linear_dist / 2.0)), error);
  } else {
    out = k * error;
  }
  // never ask for more than closes the error in one step
  if (dt_s > 0.0) out = std::clamp(out, -std::abs(error) / dt_s, std::abs(error) / dt_s);
  return out;
}

void PositionController::reset() {
  vel_x_.reset();
  vel_y_.reset();
  acc_z_.reset();
  acc_err_z_filt_ = 0.0;
  vel_target_enu_m_s_.setZero();
  accel_target_enu_m_s2_.setZero();
}

Eigen::Vector3d PositionController::update(const EstimatedState& est, double accel_z_est_m_s2,
                                           const PositionSetpoint& sp, const ParamValues& p,
                                           const DerivedParams& d, double mass_kg, double dt_s,
                                           const ThrustLimits& limits) {
  const double accel_xy_max = kGravityM_S2 * d.tan_angle_max;
  Eigen::Vector3d accel = sp.accel_enu_m_s2;
  // horizontal: position -> velocity -> acceleration
  if (sp.use_vel_xy) {
    Eigen::Vector2d vel_t = sp.velocity_enu_m_s.head<2>();
    if (sp.use_pos_xy) {
      const Eigen::Vector2d err = sp.position_enu_m.head<2>() - est.position_enu_m.head<2>();
      const double dist = err.norm();
      if (dist > 1e-9) {
        vel_t += err / dist * sqrt_controller(dist, p.psc_posxy_p, d.wp_accel_m_s2, dt_s);
      }
    }
    // limit to the navigation speed (a little above, so feed-forward plus correction still fits)
    const double vmax = 1.2 * d.wp_speed_m_s;
    if (vel_t.norm() > vmax) vel_t *= vmax / vel_t.norm();
    vel_target_enu_m_s_.head<2>() = vel_t;
    const Eigen::Vector2d vel_err = vel_t - est.velocity_enu_m_s.head<2>();
    const PidGains g{p.psc_velxy_p, p.psc_velxy_i, p.psc_velxy_d, d.velxy_imax_m_s2, kVelDCutoffHz};
    const bool saturated = accel.head<2>().norm() >= accel_xy_max;
    accel.x() += vel_x_.update(vel_err.x(), dt_s, g, saturated);
    accel.y() += vel_y_.update(vel_err.y(), dt_s, g, saturated);
  } else {
    vel_target_enu_m_s_.head<2>() = est.velocity_enu_m_s.head<2>();
    vel_x_.reset();
    vel_y_.reset();
  }
  // lean-angle limit: the horizontal acceleration a level thrust vector can give at ANGLE_MAX
  const double a_xy = accel.head<2>().norm();
  if (a_xy > accel_xy_max) accel.head<2>() *= accel_xy_max / a_xy;

  // vertical: position -> climb rate -> acceleration
  double vz_t = sp.velocity_enu_m_s.z();
  if (sp.use_pos_z) {
    vz_t += sqrt_controller(sp.position_enu_m.z() - est.position_enu_m.z(), p.psc_posz_p,
                            d.wp_accel_z_m_s2, dt_s);
  }
  vz_t = std::clamp(vz_t, -std::max(d.wp_speed_dn_m_s, d.land_speed_high_m_s),
                    std::max(d.wp_speed_up_m_s, d.pilot_speed_up_m_s));
  vel_target_enu_m_s_.z() = vz_t;
  double az_t = accel.z() + p.psc_velz_p * (vz_t - est.velocity_enu_m_s.z());
  // never command more than free fall, nor more than ~2 g up
  az_t = std::clamp(az_t, -0.8 * kGravityM_S2, 2.0 * kGravityM_S2);
  accel.z() = az_t;
  accel_target_enu_m_s2_ = accel;

  // acceleration error PID: removes thrust model errors (mass, drag) that the feed-forward misses
  const double alpha = dt_s > 0.0 ? dt_s / (dt_s + 1.0 / (2.0 * kPi * kAccErrCutoffHz)) : 0.0;
  acc_err_z_filt_ += alpha * ((az_t - accel_z_est_m_s2) - acc_err_z_filt_);
  const PidGains gz{p.psc_accz_p, p.psc_accz_i, 0.0, d.accz_imax_m_s2, 0.0};
  // anti-windup upward only: a mixer that raises thrust to keep attitude (on the ground, against the
  // contact) must not stop the integrator from lowering thrust, or the land detector never fires
  const bool freeze = acc_err_z_filt_ > 0.0 && limits.thrust_up;
  const double az_corr = acc_z_.update(acc_err_z_filt_, dt_s, gz, freeze);

  // thrust vector: m (a + g)
  Eigen::Vector3d thrust = mass_kg * accel;
  thrust.z() = mass_kg * std::max(kGravityM_S2 + az_t + az_corr, 0.0);
  return thrust;
}

}  // namespace uavsim::server::fc
