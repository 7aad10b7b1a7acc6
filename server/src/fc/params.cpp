#include "fc/params.hpp"
#include "fc/angles.hpp"

#include <cmath>

namespace uavsim::server::fc {

namespace {

// One row of the table: name, field, accepted range. The order of kTable is the MAVLink param_index;
// append new rows at the end so indices stay stable.
struct ParamDef {
  const char* name;
  double ParamValues::*field;
  double min;
  double max;
  ParamKind kind;  // ArduPilot's storage type (AP_Int8/16/32 or AP_Float)
};

constexpr ParamDef kTable[] = {
    {"SYSID_THISMAV", &ParamValues::sysid_thismav, 1, 255, ParamKind::kInt16},
    {"PSC_POSXY_P", &ParamValues::psc_posxy_p, 0, 10, ParamKind::kFloat},
    {"PSC_VELXY_P", &ParamValues::psc_velxy_p, 0, 20, ParamKind::kFloat},
    {"PSC_VELXY_I", &ParamValues::psc_velxy_i, 0, 20, ParamKind::kFloat},
    {"PSC_VELXY_D", &ParamValues::psc_velxy_d, 0, 10, ParamKind::kFloat},
    {"PSC_VELXY_IMAX", &ParamValues::psc_velxy_imax, 0, 5000, ParamKind::kFloat},
    {"PSC_POSZ_P", &ParamValues::psc_posz_p, 0, 10, ParamKind::kFloat},
    {"PSC_VELZ_P", &ParamValues::psc_velz_p, 0, 30, ParamKind::kFloat},
    {"PSC_ACCZ_P", &ParamValues::psc_accz_p, 0, 10, ParamKind::kFloat},
    {"PSC_ACCZ_I", &ParamValues::psc_accz_i, 0, 10, ParamKind::kFloat},
    {"PSC_ACCZ_IMAX", &ParamValues::psc_accz_imax, 0, 2000, ParamKind::kFloat},
    {"ATC_ANG_RLL_P", &ParamValues::atc_ang_rll_p, 0, 30, ParamKind::kFloat},
    {"ATC_ANG_PIT_P", &ParamValues::atc_ang_pit_p, 0, 30, ParamKind::kFloat},
    {"ATC_ANG_YAW_P", &ParamValues::atc_ang_yaw_p, 0, 30, ParamKind::kFloat},
    {"ATC_RAT_RLL_P", &ParamValues::atc_rat_rll_p, 0, 200, ParamKind::kFloat},
    {"ATC_RAT_RLL_I", &ParamValues::atc_rat_rll_i, 0, 200, ParamKind::kFloat},
    {"ATC_RAT_RLL_D", &ParamValues::atc_rat_rll_d, 0, 10, ParamKind::kFloat},
    {"ATC_RAT_RLL_IMAX", &ParamValues::atc_rat_rll_imax, 0, 200, ParamKind::kFloat},
    {"ATC_RAT_RLL_FLTD", &ParamValues::atc_rat_rll_fltd, 1, 200, ParamKind::kFloat},
    {"ATC_RAT_PIT_P", &ParamValues::atc_rat_pit_p, 0, 200, ParamKind::kFloat},
    {"ATC_RAT_PIT_I", &ParamValues::atc_rat_pit_i, 0, 200, ParamKind::kFloat},
    {"ATC_RAT_PIT_D", &ParamValues::atc_rat_pit_d, 0, 10, ParamKind::kFloat},
    {"ATC_RAT_PIT_IMAX", &ParamValues::atc_rat_pit_imax, 0, 200, ParamKind::kFloat},
    {"ATC_RAT_PIT_FLTD", &ParamValues::atc_rat_pit_fltd, 1, 200, ParamKind::kFloat},
    {"ATC_RAT_YAW_P", &ParamValues::atc_rat_yaw_p, 0, 200, ParamKind::kFloat},
    {"ATC_RAT_YAW_I", &ParamValues::atc_rat_yaw_i, 0, 200, ParamKind::kFloat},
    {"ATC_RAT_YAW_IMAX", &ParamValues::atc_rat_yaw_imax, 0, 200, ParamKind::kFloat},
    {"ATC_RATE_RP_MAX", &ParamValues::atc_rate_rp_max, 10, 1080, ParamKind::kFloat},
    {"ATC_RATE_Y_MAX", &ParamValues::atc_rate_y_max, 5, 1080, ParamKind::kFloat},
    {"ATC_SLEW_YAW", &ParamValues::atc_slew_yaw, 500, 18000, ParamKind::kFloat},
    {"ANGLE_MAX", &ParamValues::angle_max, 1000, 8000, ParamKind::kInt16},
    {"WPNAV_SPEED", &ParamValues::wpnav_speed, 20, 2000, ParamKind::kFloat},
    {"WPNAV_SPEED_UP", &ParamValues::wpnav_speed_up, 10, 1000, ParamKind::kFloat},
    {"WPNAV_SPEED_DN", &ParamValues::wpnav_speed_dn, 10, 500, ParamKind::kFloat},
    {"WPNAV_ACCEL", &ParamValues::wpnav_accel, 50, 500, ParamKind::kFloat},
    {"WPNAV_ACCEL_Z", &ParamValues::wpnav_accel_z, 50, 500, ParamKind::kFloat},
    {"WPNAV_RADIUS", &ParamValues::wpnav_radius, 5, 1000, ParamKind::kFloat},
    {"WP_YAW_BEHAVIOR", &ParamValues::wp_yaw_behavior, 0, 3, ParamKind::kInt8},
    {"LAND_SPEED", &ParamValues::land_speed, 30, 200, ParamKind::kInt16},
    {"LAND_SPEED_HIGH", &ParamValues::land_speed_high, 0, 500, ParamKind::kInt16},
    {"RTL_ALT", &ParamValues::rtl_alt, 200, 300000, ParamKind::kInt32},
    {"RTL_SPEED", &ParamValues::rtl_speed, 0, 2000, ParamKind::kInt16},
    {"RTL_LOIT_TIME", &ParamValues::rtl_loit_time, 0, 60000, ParamKind::kInt32},
    {"PILOT_TKOFF_ALT", &ParamValues::pilot_tkoff_alt, 0, 1000, ParamKind::kFloat},
    {"PILOT_SPEED_UP", &ParamValues::pilot_speed_up, 50, 500, ParamKind::kInt16},
    {"PILOT_SPEED_DN", &ParamValues::pilot_speed_dn, 0, 500, ParamKind::kInt16},
    {"FS_GCS_ENABLE", &ParamValues::fs_gcs_enable, 0, 1, ParamKind::kInt8},
    {"FS_GCS_TIMEOUT", &ParamValues::fs_gcs_timeout, 2, 120, ParamKind::kFloat},
    {"FS_BATT_ENABLE", &ParamValues::fs_batt_enable, 0, 2, ParamKind::kInt8},
    {"BATT_CAPACITY", &ParamValues::batt_capacity, 0, 1e6, ParamKind::kInt32},
    {"BATT_LOW_MAH", &ParamValues::batt_low_mah, 0, 1e6, ParamKind::kFloat},
    {"FS_EKF_ACTION", &ParamValues::fs_ekf_action, 0, 1, ParamKind::kInt8},
    {"ARMING_CHECK", &ParamValues::arming_check, 0, 1, ParamKind::kInt32},
    {"DISARM_DELAY", &ParamValues::disarm_delay, 0, 127, ParamKind::kInt8},
    {"MOT_SPIN_ARM", &ParamValues::mot_spin_arm, 0, 0.2, ParamKind::kFloat},
    {"GUID_TIMEOUT", &ParamValues::guid_timeout, 0.1, 5, ParamKind::kFloat},
    {"SIM_GPS_HZ", &ParamValues::sim_gps_hz, 1, 50, ParamKind::kInt8},
    {"SIM_GPS_POS_H_SD", &ParamValues::sim_gps_pos_h_sd, 0, 100, ParamKind::kFloat},
    {"SIM_GPS_POS_V_SD", &ParamValues::sim_gps_pos_v_sd, 0, 100, ParamKind::kFloat},
    {"SIM_GPS_VEL_SD", &ParamValues::sim_gps_vel_sd, 0, 10, ParamKind::kFloat},
    {"SIM_GPS_NUMSATS", &ParamValues::sim_gps_numsats, 0, 50, ParamKind::kInt8},
    {"SIM_GPS_HDOP", &ParamValues::sim_gps_hdop, 0.1, 99.99, ParamKind::kFloat},
    {"SIM_BARO_HZ", &ParamValues::sim_baro_hz, 1, 500, ParamKind::kFloat},
    {"SIM_BARO_SD", &ParamValues::sim_baro_sd, 0, 10, ParamKind::kFloat},
    {"SIM_MAG_HZ", &ParamValues::sim_mag_hz, 1, 500, ParamKind::kFloat},
    {"SIM_MAG_SD", &ParamValues::sim_mag_sd, 0, 1, ParamKind::kFloat},
    {"SIM_GYRO_SD", &ParamValues::sim_gyro_sd, 0, 1, ParamKind::kFloat},
    {"SIM_ACCEL_SD", &ParamValues::sim_accel_sd, 0, 10, ParamKind::kFloat},
    {"RC_OVERRIDE_TIME", &ParamValues::rc_override_time, -1, 120, ParamKind::kFloat},
    {"SIM_GPS_BIAS_SD", &ParamValues::sim_gps_bias_sd, 0, 100, ParamKind::kFloat},
    {"SIM_GPS_BIAS_TAU", &ParamValues::sim_gps_bias_tau, 1, 36000, ParamKind::kFloat},
    {"SIM_GPS_JUMP_HZ", &ParamValues::sim_gps_jump_hz, 0, 1, ParamKind::kFloat},
    {"SIM_GPS_JUMP_M", &ParamValues::sim_gps_jump_m, 0, 100, ParamKind::kFloat},
    {"SIM_GPS_RTK", &ParamValues::sim_gps_rtk, 0, 1, ParamKind::kInt8},
    {"SIM_BARO_DRIFT", &ParamValues::sim_baro_drift, 0, 100, ParamKind::kFloat},
    {"SIM_MAG_OFS_SD", &ParamValues::sim_mag_ofs_sd, 0, 1, ParamKind::kFloat},
};

const ParamDef* find(std::string_view name) {
  for (const ParamDef& def : kTable) {
    if (name == def.name) return &def;
  }
  return nullptr;
}

}  // namespace

std::vector<ParamInfo> param_info(double battery_capacity_mah) {
  const ParamTable defaults(battery_capacity_mah);
  std::vector<ParamInfo> out;
  out.reserve(std::size(kTable));
  for (const ParamDef& def : kTable) out.push_back({def.name, def.min, def.max, *defaults.get(def.name), def.kind});
  return out;
}

ParamTable::ParamTable(double battery_capacity_mah) {
  if (std::isfinite(battery_capacity_mah) && battery_capacity_mah > 0.0) {
    values_.batt_capacity = battery_capacity_mah;
    values_.batt_low_mah = 0.2 * battery_capacity_mah;
  }
  names_.reserve(std::size(kTable));
  for (const ParamDef& def : kTable) names_.emplace_back(def.name);
  derive();
}

std::optional<ParamKind> ParamTable::kind(std::string_view name) const {
  const ParamDef* def = find(name);
  if (def == nullptr) return std::nullopt;
  return def->kind;
}

std::optional<double> ParamTable::get(std::string_view name) const {
  const ParamDef* def = find(name);
  if (def == nullptr) return std::nullopt;
  return values_.*(def->field);
}

double stored_value(ParamKind kind, double value) {
  if (kind == ParamKind::kFloat) return value;
  // an integer parameter keeps the whole part, as ArduPilot's AP_Param::set_float stores a float into
  // an AP_Int: 0.01 away from zero first, so that 2.9999998 (2 + 1 ulp of float error) is still 3
  return std::trunc(value + (value < 0.0 ? -0.01 : 0.01));
}

bool ParamTable::set(std::string_view name, double value) {
  const ParamDef* def = find(name);
  if (def == nullptr || !std::isfinite(value)) return false;
  value = stored_value(def->kind, value);
  if (value < def->min || value > def->max) return false;
  values_.*(def->field) = value;
  derive();
  return true;
}

void ParamTable::derive() {
  const ParamValues& v = values_;
  DerivedParams& d = derived_;
  // ArduPilot units (cdeg, cm, cm/s, ms) to SI
  d.angle_max_rad = v.angle_max * 0.01 * kDegToRad;
  d.tan_angle_max = std::tan(d.angle_max_rad);
  d.rate_rp_max_rad_s = v.atc_rate_rp_max * kDegToRad;
  d.rate_y_max_rad_s = v.atc_rate_y_max * kDegToRad;
  d.slew_yaw_rad_s = v.atc_slew_yaw * 0.01 * kDegToRad;
  d.wp_speed_m_s = v.wpnav_speed * 0.01;
  d.wp_speed_up_m_s = v.wpnav_speed_up * 0.01;
  d.wp_speed_dn_m_s = v.wpnav_speed_dn * 0.01;
  d.wp_accel_m_s2 = v.wpnav_accel * 0.01;
  d.wp_accel_z_m_s2 = v.wpnav_accel_z * 0.01;
  d.wp_radius_m = v.wpnav_radius * 0.01;
  d.velxy_imax_m_s2 = v.psc_velxy_imax * 0.01;
  d.accz_imax_m_s2 = v.psc_accz_imax * 0.01;
  d.land_speed_m_s = v.land_speed * 0.01;
  // as ArduCopter: 0 means "use WPNAV_SPEED_DN", and RTL_SPEED 0 means "use WPNAV_SPEED"
  d.land_speed_high_m_s = (v.land_speed_high > 0.0 ? v.land_speed_high : v.wpnav_speed_dn) * 0.01;
  d.rtl_alt_m = v.rtl_alt * 0.01;
  d.rtl_speed_m_s = (v.rtl_speed > 0.0 ? v.rtl_speed : v.wpnav_speed) * 0.01;
  d.rtl_loit_time_s = v.rtl_loit_time * 0.001;
  d.pilot_tkoff_alt_m = v.pilot_tkoff_alt * 0.01;
  d.pilot_speed_up_m_s = v.pilot_speed_up * 0.01;
  d.pilot_speed_dn_m_s = (v.pilot_speed_dn > 0.0 ? v.pilot_speed_dn : v.pilot_speed_up) * 0.01;
}

}  // namespace uavsim::server::fc
