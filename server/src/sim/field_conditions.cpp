#include "sim/field_conditions.hpp"
#include "uavsim/common/angles.hpp"

namespace uavsim::server::sim {

const char* realism_name(Realism realism) { return realism == Realism::kField ? "field" : "ideal"; }

std::optional<Realism> realism_from_name(const std::string& name) {
  if (name == "ideal") return Realism::kIdeal;
  if (name == "field") return Realism::kField;
  return std::nullopt;
}

FieldConditions field_conditions(Realism realism) {
  FieldConditions c;
  c.realism = realism;
  if (realism == Realism::kIdeal) return c;
  // wind: a fresh breeze over open desert, moderate turbulence, a gust now and then; any direction
  c.wind.speed_m_s = 4.0;
  c.wind.turbulence_sd_m_s = 1.0;
  c.wind.length_scale_m = 30.0;
  c.wind.gust_rate_hz = 1.0 / 60.0;
  c.wind.gust_m_s = 3.0;
  c.wind.gust_duration_s = 3.0;
  c.wind_from_seeded = true;
  // a 5 Ah 3S LiPo of 25C class: ~15 mOhm for the pack and its wiring
  c.battery_resistance_ohm = 0.015;
  // a small brushless 2-axis gimbal: 50 ms loop, 180 deg/s, 1000 deg/s^2
  c.gimbal.time_const_s = 0.05;
  c.gimbal.rate_max_rad_s = 180.0 * common::kPi / 180.0;
  c.gimbal.accel_max_rad_s2 = 1000.0 * common::kPi / 180.0;
  c.balloons.height_spread_m = 0.5;
  c.balloons.sway = true;
  // a standalone u-blox M8-class GPS: wandering bias, jumps; baro drift; a residual compass offset
  c.sensor_params = {
      {"SIM_GPS_POS_H_SD", 0.15}, {"SIM_GPS_POS_V_SD", 0.3},   {"SIM_GPS_VEL_SD", 0.1},
      {"SIM_GPS_BIAS_SD", 0.7},   {"SIM_GPS_BIAS_TAU", 120.0}, {"SIM_GPS_JUMP_HZ", 1.0 / 300.0},
      {"SIM_GPS_JUMP_M", 1.5},    {"SIM_BARO_DRIFT", 0.5},     {"SIM_MAG_OFS_SD", 0.05}};
  // a small global-shutter CMOS camera over USB: read noise, auto-exposure wander, 60 ms late; its depth
  // (where a camera gives depth) as a small-baseline stereo pair has it: 0.1 px of disparity error at a
  // 12 cm baseline and f = 400 px is sd(z) = 0.1 z^2 / (400 * 0.12) = 0.002 z^2, a few percent of the
  // pixels unmatched, nothing beyond 40 m
  c.camera_settings =
      "noise=3,brightness=0.08,latency_ms=60,depth_noise=0.002,depth_dropout=0.03,depth_max_m=40";
  return c;
}

}  // namespace uavsim::server::sim
