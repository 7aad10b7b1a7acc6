#include "fc/sensors.hpp"

#include <cmath>

namespace uavsim::server::fc {

namespace {
// half a microsecond of slack so a sample due exactly at a control step is not pushed to the next one
constexpr double kDueSlackS = 5e-7;
}  // namespace

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
    const Eigen::Vector3d pos_noise(gauss(p.sim_gps_pos_h_sd), gauss(p.sim_gps_pos_h_sd),
                                    gauss(p.sim_gps_pos_v_sd));
    const Eigen::Vector3d vel_noise(gauss(p.sim_gps_vel_sd), gauss(p.sim_gps_vel_sd),
                                    gauss(p.sim_gps_vel_sd));
    if (gps_denied_) {
      g.fix_3d = false;
      g.satellites = 0;
      g.hdop = 99.99;
    } else {
      g.position_enu_m = truth.position_enu_m + pos_noise + gps_glitch_enu_m_;
      g.velocity_enu_m_s = truth.velocity_enu_m_s + vel_noise;
      g.satellites = static_cast<int>(p.sim_gps_numsats);
      g.hdop = p.sim_gps_hdop;
      // a 3D fix needs at least 6 satellites, as ArduPilot's GPS_MIN_SATS-ish rule of thumb
      g.fix_3d = g.satellites >= 6;
    }
  }

  // barometer: altitude of the origin plane + white noise
  out->baro_new = due(time_s, p.sim_baro_hz, &next_baro_s_);
  if (out->baro_new) out->baro_alt_m = truth.position_enu_m.z() + gauss(p.sim_baro_sd);

  // compass: heading of body x in ENU (yaw), + white noise
  out->mag_new = due(time_s, p.sim_mag_hz, &next_mag_s_);
  if (out->mag_new) {
    const Eigen::Vector3d x_enu = R_enu_body.col(0);
    out->heading_enu_rad = std::atan2(x_enu.y(), x_enu.x()) + gauss(p.sim_mag_sd);
  }
}

}  // namespace uavsim::server::fc
