#include "fc/sensors.hpp"

#include <cmath>

namespace uavsim::server::fc {

namespace {
// half a microsecond of slack so a sample due exactly at a control step is not pushed to the next one
constexpr double kDueSlackS = 5e-7;
constexpr double kBaroDriftTau_s = 300.0;  // weather and temperature drift of a MEMS barometer
constexpr double kRtkPosH_m = 0.01;
constexpr double kRtkPosV_m = 0.02;
constexpr double kRtkVel_m_s = 0.02;
constexpr uint64_t kErrorStream = 0xE7707ull;

// one exact Gauss-Markov step of x over dt (stationary sd, correlation time tau), n ~ N(0, 1)
double gauss_markov(double x, double sd, double tau_s, double dt_s, double n) {
  const double a = std::exp(-dt_s / tau_s);
  return a * x + sd * std::sqrt(1.0 - a * a) * n;
}
}  // namespace

Sensors::Sensors(uint64_t seed) : noise_(seed), errors_(seed ^ kErrorStream) {
  mag_offset_unit_ = errors_();
}

bool Sensors::due(double time_s, double rate_hz, double* next_s) {
  if (time_s + kDueSlackS < *next_s) return false;
  const double period_s = 1.0 / rate_hz;
  *next_s += period_s;
  // after a gap (first call, pause) restart the schedule from now rather than catching up
  if (*next_s <= time_s) *next_s = time_s + period_s;
  return true;
}

void Sensors::sample(double time_s, const TruthState& truth, const ParamValues& p,
                     SensorFrame* out) {
  const Eigen::Matrix3d R_enu_body = truth.q_enu_body.toRotationMatrix();
  // imu: gyro = body rate + noise; accelerometer = specific force R^T (a + g), g pointing up in ENU
  const Eigen::Vector3d g_enu(0.0, 0.0, kGravityM_S2);
  out->imu.gyro_body_rad_s = truth.rate_body_rad_s;
  out->imu.accel_body_m_s2 = R_enu_body.transpose() * (truth.accel_enu_m_s2 + g_enu);
  for (int i = 0; i < 3; ++i) out->imu.gyro_body_rad_s[i] += gauss(p.sim_gyro_sd);
  for (int i = 0; i < 3; ++i) out->imu.accel_body_m_s2[i] += gauss(p.sim_accel_sd);

  // gps: white position and velocity noise, plus the injected glitch offset; nothing while denied
  out->gps_new = due(time_s, p.sim_gps_hz, &next_gps_s_);
  if (out->gps_new) {
    GpsSample& g = out->gps;
    // draw the noise even while denied so the sequence does not depend on fault timing
    const bool rtk = p.sim_gps_rtk >= 0.5;
    const double h_sd = rtk ? kRtkPosH_m : p.sim_gps_pos_h_sd;
    const double v_sd = rtk ? kRtkPosV_m : p.sim_gps_pos_v_sd;
    const double vel_sd = rtk ? kRtkVel_m_s : p.sim_gps_vel_sd;
    const Eigen::Vector3d pos_noise(gauss(h_sd), gauss(h_sd), gauss(v_sd));
    const Eigen::Vector3d vel_noise(gauss(vel_sd), gauss(vel_sd), gauss(vel_sd));
    // field: the wandering bias and its jumps (second generator), none in RTK
    if (!rtk && (p.sim_gps_bias_sd > 0 || p.sim_gps_jump_hz > 0)) {
      const double sd[3] = {p.sim_gps_bias_sd, p.sim_gps_bias_sd, 2.0 * p.sim_gps_bias_sd};
      const double period_s = 1.0 / p.sim_gps_hz;
      for (int i = 0; i < 3; ++i) {
        const double n = errors_();
        gps_bias_enu_m_[i] = gps_bias_started_ ? gauss_markov(gps_bias_enu_m_[i], sd[i], p.sim_gps_bias_tau, period_s, n)
                                               : sd[i] * n;
      }
      gps_bias_started_ = true;
      if (errors_.uniform() < p.sim_gps_jump_hz * period_s) {
        for (int i = 0; i < 3; ++i) gps_bias_enu_m_[i] += (i < 2 ? 1.0 : 2.0) * p.sim_gps_jump_m * errors_();
      }
    } else {
      gps_bias_enu_m_.setZero();
      gps_bias_started_ = false;
    }
    if (gps_denied_) {
      g.fix_3d = false;
      g.satellites = 0;
      g.hdop = 99.99;
    } else {
      g.position_enu_m = truth.position_enu_m + pos_noise + gps_bias_enu_m_ + gps_glitch_enu_m_;
      g.velocity_enu_m_s = truth.velocity_enu_m_s + vel_noise;
      g.satellites = static_cast<int>(p.sim_gps_numsats);
      g.hdop = p.sim_gps_hdop;
      // a 3D fix needs at least 6 satellites, as ArduPilot's GPS_MIN_SATS-ish rule of thumb
      g.fix_3d = g.satellites >= 6;
    }
  }

  // barometer: altitude of the origin plane + white noise
  out->baro_new = due(time_s, p.sim_baro_hz, &next_baro_s_);
  if (out->baro_new) {
    if (p.sim_baro_drift > 0) {
      const double n = errors_();
      baro_drift_m_ = baro_drift_started_
                          ? gauss_markov(baro_drift_m_, p.sim_baro_drift, kBaroDriftTau_s, 1.0 / p.sim_baro_hz, n)
                          : p.sim_baro_drift * n;
      baro_drift_started_ = true;
    }
    out->baro_alt_m = truth.position_enu_m.z() + gauss(p.sim_baro_sd) + baro_drift_m_;
  }

  // compass: heading of body x in ENU (yaw), + white noise
  out->mag_new = due(time_s, p.sim_mag_hz, &next_mag_s_);
  if (out->mag_new) {
    const Eigen::Vector3d x_enu = R_enu_body.col(0);
    out->heading_enu_rad =
        std::atan2(x_enu.y(), x_enu.x()) + gauss(p.sim_mag_sd) + p.sim_mag_ofs_sd * mag_offset_unit_;
  }
}

}  // namespace uavsim::server::fc
