#include "fc/estimator.hpp"
#include "fc/angles.hpp"

#include <algorithm>
#include <cmath>

namespace uavsim::server::fc {

namespace {

// attitude correction gains, rad/s per unit error: slow for gravity (the accelerometer sees vibration
// and manoeuvres), faster for heading
constexpr double kAccelCorrectionGain = 0.1;
// for the first seconds after initialisation the gravity correction is fast (the vehicle sits still):
// the first accelerometer samples may be taken while the landing gear settles on the ground, and a
// tilt error left from them would otherwise take tens of seconds to decay (ArduPilot's DCM also uses
// high gains before arming)
constexpr double kFastAlignGain = 2.0;
constexpr double kFastAlignS = 2.0;
constexpr double kMagCorrectionGain = 0.3;
// GPS-derived acceleration low-pass time constant
constexpr double kGpsAccelTauS = 0.3;
// inertial-nav time constants (ArduPilot INAV_TC_XY = 2.5 s, INAV_TC_Z = 5 s; shorter here because
// our GPS and baro have white noise only)
constexpr double kTcXyS = 1.5;
constexpr double kTcZS = 2.0;
// a GPS fix older than this is not "ok"
constexpr double kGpsTimeoutS = 0.5;
// fixes further than this from the estimate are rejected as glitches; after kGlitchResetS of
// rejections the estimate is reset to GPS (ArduPilot's EKF does the same after its innovation gate)
constexpr double kGpsGateM = 10.0;
constexpr double kGlitchResetS = 5.0;
constexpr double kSettleS = 2.0;
constexpr double kAccelZLpTauS = 0.15;


}  // namespace

double Estimator::yaw_enu_rad() const {
  const Eigen::Vector3d x_enu = state_.q_enu_body * Eigen::Vector3d::UnitX();
  return std::atan2(x_enu.y(), x_enu.x());
}

bool Estimator::converged(double time_s) const {
  return attitude_init_ && position_init_ && time_s - position_init_time_s_ >= kSettleS &&
         time_s - attitude_init_time_s_ >= kFastAlignS;
}

void Estimator::update(double time_s, double dt_s, const SensorFrame& sensors) {
  time_s_ = time_s;
  if (sensors.mag_new) {
    mag_heading_rad_ = sensors.heading_enu_rad;
    have_mag_ = true;
  }
  update_attitude(dt_s, sensors);
  update_position(time_s, dt_s, sensors);
  state_.rate_body_rad_s = sensors.imu.gyro_body_rad_s;
  state_.gps_ok = sensors.gps.fix_3d && time_s - last_gps_time_s_ <= kGpsTimeoutS;
  state_.gps_satellites = sensors.gps.satellites;
  state_.gps_hdop = sensors.gps.hdop;
}

void Estimator::update_attitude(double dt_s, const SensorFrame& sensors) {
  const Eigen::Vector3d& f_body = sensors.imu.accel_body_m_s2;
  // initialise roll/pitch from gravity and yaw from the compass, once both are available
  if (!attitude_init_) {
    if (!have_mag_ || f_body.norm() < 1e-3) return;
    const Eigen::Vector3d up_body = f_body.normalized();
    // the rotation taking body z onto measured up gives tilt; then yaw about world z
    const Eigen::Quaterniond q_tilt_inv = Eigen::Quaterniond::FromTwoVectors(up_body, Eigen::Vector3d::UnitZ());
    Eigen::Quaterniond q = q_tilt_inv;  // q_enu_body for zero yaw (up to a yaw offset)
    const Eigen::Vector3d x_enu = q * Eigen::Vector3d::UnitX();
    const double yaw0 = std::atan2(x_enu.y(), x_enu.x());
    q = Eigen::AngleAxisd(wrap_pi(mag_heading_rad_ - yaw0), Eigen::Vector3d::UnitZ()) * q;
    state_.q_enu_body = q.normalized();
    attitude_init_ = true;
    attitude_init_time_s_ = time_s_;
    return;
  }
  if (!(dt_s > 0.0)) return;

  const Eigen::Matrix3d R_enu_body = state_.q_enu_body.toRotationMatrix();
  Eigen::Vector3d omega = sensors.imu.gyro_body_rad_s;
  // gravity correction (Mahony: e = v_measured x v_estimated): measured specific force vs the
  // expected one, R^T (a_gps + g), both normalised
  const Eigen::Vector3d ref_enu = gps_accel_lp_enu_m_s2_ + Eigen::Vector3d(0.0, 0.0, kGravityM_S2);
  const double f_norm = f_body.norm();
  if (f_norm > 0.5 * kGravityM_S2 && f_norm < 1.5 * kGravityM_S2) {
    const Eigen::Vector3d v_est = (R_enu_body.transpose() * ref_enu).normalized();
    const bool aligning = time_s_ - attitude_init_time_s_ < kFastAlignS;
    omega += (aligning ? kFastAlignGain : kAccelCorrectionGain) * (f_body / f_norm).cross(v_est);
  }
  // heading correction: rotate about world z by the compass error
  if (have_mag_) {
    const Eigen::Vector3d x_enu = R_enu_body.col(0);
    const double yaw = std::atan2(x_enu.y(), x_enu.x());
    const double err = wrap_pi(mag_heading_rad_ - yaw);
    omega += R_enu_body.transpose() * Eigen::Vector3d(0.0, 0.0, kMagCorrectionGain * err);
  }
  // integrate q_dot = 0.5 q (0, omega) exactly for constant omega over dt
  const double angle = omega.norm() * dt_s;
  if (angle > 1e-12) {
    const Eigen::Quaterniond dq(Eigen::AngleAxisd(angle, omega / omega.norm()));
    state_.q_enu_body = (state_.q_enu_body * dq).normalized();
  }
}

void Estimator::update_position(double time_s, double dt_s, const SensorFrame& sensors) {
  const GpsSample& gps = sensors.gps;
  // gps: initialise, or compute the held position error (with a glitch gate)
  if (sensors.gps_new && gps.fix_3d) {
    if (last_gps_vel_time_s_ >= 0.0 && time_s > last_gps_vel_time_s_) {
      const Eigen::Vector3d a = (gps.velocity_enu_m_s - last_gps_vel_enu_m_s_) /
                                (time_s - last_gps_vel_time_s_);
      const double T = time_s - last_gps_vel_time_s_;
      gps_accel_lp_enu_m_s2_ += (a - gps_accel_lp_enu_m_s2_) * (T / (T + kGpsAccelTauS));
    }
    last_gps_vel_enu_m_s_ = gps.velocity_enu_m_s;
    last_gps_vel_time_s_ = time_s;
    last_gps_time_s_ = time_s;
    if (!position_init_) {
      state_.position_enu_m.x() = gps.position_enu_m.x();
      state_.position_enu_m.y() = gps.position_enu_m.y();
      if (!baro_init_) state_.position_enu_m.z() = gps.position_enu_m.z();
      state_.velocity_enu_m_s = gps.velocity_enu_m_s;
      position_init_ = true;
      position_init_time_s_ = time_s;
    } else {
      const Eigen::Vector2d e = gps.position_enu_m.head<2>() - state_.position_enu_m.head<2>();
      if (e.norm() > kGpsGateM) {
        if (!gps_rejecting_) gps_reject_since_s_ = time_s;
        gps_rejecting_ = true;
        pos_error_enu_m_.head<2>().setZero();
        if (time_s - gps_reject_since_s_ >= kGlitchResetS) {
          // the fixes have disagreed for too long: trust GPS again (ArduPilot's reset to GPS)
          state_.position_enu_m.head<2>() = gps.position_enu_m.head<2>();
          state_.velocity_enu_m_s.head<2>() = gps.velocity_enu_m_s.head<2>();
          gps_rejecting_ = false;
        }
      } else {
        gps_rejecting_ = false;
        pos_error_enu_m_.head<2>() = e;
      }
    }
  } else if (sensors.gps_new) {
    pos_error_enu_m_.head<2>().setZero();
    last_gps_vel_time_s_ = -1.0;
    gps_accel_lp_enu_m_s2_.setZero();
  }
  // barometer: the vertical position source (ArduPilot's default EK3_SRC1_POSZ = baro)
  if (sensors.baro_new) {
    if (!baro_init_) {
      state_.position_enu_m.z() = sensors.baro_alt_m;
      baro_init_ = true;
    }
    pos_error_enu_m_.z() = sensors.baro_alt_m - state_.position_enu_m.z();
  }
  state_.baro_alt_m = sensors.baro_alt_m;
  if (!attitude_init_ || !(dt_s > 0.0)) return;

  // predict: a = R f - g (+ bias estimate), integrate velocity and position
  const Eigen::Vector3d accel_enu = state_.q_enu_body * sensors.imu.accel_body_m_s2 -
                                    Eigen::Vector3d(0.0, 0.0, kGravityM_S2) + accel_bias_enu_m_s2_;
  state_.accel_enu_m_s2 = accel_enu;
  accel_z_lp_m_s2_ += (accel_enu.z() - accel_z_lp_m_s2_) * (dt_s / (dt_s + kAccelZLpTauS));
  state_.velocity_enu_m_s += accel_enu * dt_s;
  state_.position_enu_m += state_.velocity_enu_m_s * dt_s;
  // correct: third-order complementary filter on the held position error
  for (int i = 0; i < 3; ++i) {
    const double tc = i < 2 ? kTcXyS : kTcZS;
    const double k1 = 3.0 / tc, k2 = 3.0 / (tc * tc), k3 = 1.0 / (tc * tc * tc);
    const double e = pos_error_enu_m_[i];
    state_.position_enu_m[i] += k1 * e * dt_s;
    state_.velocity_enu_m_s[i] += k2 * e * dt_s;
    accel_bias_enu_m_s2_[i] += k3 * e * dt_s;
  }
}

}  // namespace uavsim::server::fc
