// The flight controller's live parameter table: ArduPilot names and units (cm, cm/s, cdeg, ms) where
// ArduPilot has the parameter, our own names (UAVSIM-style, same naming pattern) where it has not.
//
// Raw values live in plain struct fields (one per parameter) so the control step reads fields, never a
// map; derive() converts them to SI once per set_param, never in the hot path.
#pragma once

#include <array>
#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace uavsim::server::fc {

// Raw parameter values, in ArduPilot units. Gains of the rate loop are in (rad/s^2)/(rad/s): the FC
// multiplies the rate-PID output by the airframe inertia, so one set of gains suits any vehicle size.
struct ParamValues {
  // position controller (PSC_*): accelerations in m/s^2 per unit error, as in ArduPilot
  double psc_posxy_p = 1.0;
  double psc_velxy_p = 2.0;
  double psc_velxy_i = 1.0;
  // 0.25, not more: GPS position noise (SIM_GPS_POS_H_SD, a new fix every 0.1 s) steps the slope of
  // the estimated velocity, and the D term turned each step into a tilt kick; at 0.5 it was most of
  // the hover body-rate jitter (quad 0.055 rad/s RMS, 0.034 at 0.25; gyro noise and the rate D term
  // contribute almost nothing)
  double psc_velxy_d = 0.25;
  double psc_velxy_imax = 1000.0;  // cm/s^2
  double psc_posz_p = 1.0;
  double psc_velz_p = 5.0;
  double psc_accz_p = 0.5;
  double psc_accz_i = 1.0;
  double psc_accz_imax = 500.0;    // cm/s^2 (ArduPilot: throttle permille; here an acceleration)
  // attitude controller (ATC_*): angle P in (rad/s)/rad, rate PID in (rad/s^2)/(rad/s)
  double atc_ang_rll_p = 6.0;
  double atc_ang_pit_p = 6.0;
  double atc_ang_yaw_p = 3.0;
  double atc_rat_rll_p = 20.0;
  double atc_rat_rll_i = 10.0;
  double atc_rat_rll_d = 0.3;
  double atc_rat_rll_imax = 20.0;  // rad/s^2
  double atc_rat_rll_fltd = 30.0;  // Hz, D-term low-pass
  double atc_rat_pit_p = 20.0;
  double atc_rat_pit_i = 10.0;
  double atc_rat_pit_d = 0.3;
  double atc_rat_pit_imax = 20.0;
  double atc_rat_pit_fltd = 30.0;
  double atc_rat_yaw_p = 8.0;
  double atc_rat_yaw_i = 2.0;
  double atc_rat_yaw_imax = 5.0;
  double atc_rate_rp_max = 360.0;  // deg/s (ArduPilot ATC_RATE_R_MAX/P_MAX; 0 there = unlimited)
  double atc_rate_y_max = 90.0;    // deg/s
  double atc_slew_yaw = 6000.0;    // cdeg/s, slew of the yaw target
  double angle_max = 3000.0;       // cdeg
  // waypoint navigation (cm, cm/s, cm/s^2)
  double wpnav_speed = 1000.0;
  double wpnav_speed_up = 250.0;
  double wpnav_speed_dn = 150.0;
  double wpnav_accel = 250.0;
  double wpnav_accel_z = 100.0;
  double wpnav_radius = 200.0;
  double wp_yaw_behavior = 2.0;    // 0: keep yaw, 2: face the next waypoint except in RTL
  // landing and return
  double land_speed = 50.0;        // cm/s, final descent
  double land_speed_high = 0.0;    // cm/s above 10 m; 0: WPNAV_SPEED_DN
  double rtl_alt = 1500.0;         // cm above home
  double rtl_speed = 0.0;          // cm/s; 0: WPNAV_SPEED
  double rtl_loit_time = 5000.0;   // ms over home before descending
  double pilot_tkoff_alt = 0.0;    // cm: take-off altitude when takeoff() is given 0
  double pilot_speed_up = 250.0;   // cm/s: user take-off climb rate and ATTITUDE_TARGET thrust scale
  double pilot_speed_dn = 0.0;     // cm/s; 0: PILOT_SPEED_UP
  // failsafes
  double fs_gcs_enable = 0.0;      // 0 off, 1 RTL (ArduPilot default 0)
  double fs_gcs_timeout = 5.0;     // s
  double fs_batt_enable = 0.0;     // 0 off, 1 LAND, 2 RTL
  double batt_capacity = 5000.0;   // mAh (set from the airframe)
  double batt_low_mah = 1000.0;    // mAh remaining that triggers the battery failsafe
  double fs_ekf_action = 1.0;      // 0 off, 1 LAND when GPS is lost in a position mode
  // arming and landing
  double arming_check = 1.0;       // 0: skip the pre-arm checks, 1: all
  double disarm_delay = 10.0;      // s on the ground before auto-disarm; 0: never
  double mot_spin_arm = 0.10;      // motor command while armed on the ground
  double guid_timeout = 3.0;       // s, velocity/accel/attitude targets in GUIDED
  double sysid_thismav = 1.0;
  double rc_override_time = 3.0;   // s an RC override lasts (ArduPilot RC_OVERRIDE_TIME; 0 off, -1 forever)
  // sensors (not ArduPilot parameters: the simulated hardware's noise, changeable for experiments)
  double sim_gps_hz = 10.0;
  double sim_gps_pos_h_sd = 0.05;  // m
  double sim_gps_pos_v_sd = 0.10;  // m
  double sim_gps_vel_sd = 0.05;    // m/s
  double sim_gps_numsats = 12.0;
  double sim_gps_hdop = 0.7;
  double sim_baro_hz = 50.0;
  double sim_baro_sd = 0.05;       // m
  double sim_mag_hz = 50.0;
  double sim_mag_sd = 0.02;        // rad of heading
  double sim_gyro_sd = 0.003;      // rad/s
  double sim_accel_sd = 0.03;      // m/s^2
  // field sensor errors (sim/field_conditions.hpp; 0 = off, the ideal world)
  double sim_gps_bias_sd = 0.0;    // m: stationary sd of the wandering horizontal GPS bias (Gauss-Markov)
  double sim_gps_bias_tau = 120.0; // s: its correlation time (vertical: the same, twice the sd)
  double sim_gps_jump_hz = 0.0;    // mean rate of bias jumps (a satellite lost or gained, multipath)
  double sim_gps_jump_m = 0.0;     // m: sd of a jump's horizontal size; it then decays with the bias
  double sim_gps_rtk = 0.0;        // 1: RTK fixed: 1 cm / 2 cm white noise, no bias or jumps
  double sim_baro_drift = 0.0;     // m: stationary sd of the barometer's drift (Gauss-Markov, 300 s)
  double sim_mag_ofs_sd = 0.0;     // rad: sd of the compass heading offset drawn once per vehicle
};

// SI values derived from ParamValues by derive(); what the control step actually reads.
struct DerivedParams {
  double angle_max_rad = 0.0;
  double tan_angle_max = 0.0;
  double rate_rp_max_rad_s = 0.0;
  double rate_y_max_rad_s = 0.0;
  double slew_yaw_rad_s = 0.0;
  double wp_speed_m_s = 0.0;
  double wp_speed_up_m_s = 0.0;
  double wp_speed_dn_m_s = 0.0;
  double wp_accel_m_s2 = 0.0;
  double wp_accel_z_m_s2 = 0.0;
  double wp_radius_m = 0.0;
  double velxy_imax_m_s2 = 0.0;
  double accz_imax_m_s2 = 0.0;
  double land_speed_m_s = 0.0;
  double land_speed_high_m_s = 0.0;
  double rtl_alt_m = 0.0;
  double rtl_speed_m_s = 0.0;
  double rtl_loit_time_s = 0.0;
  double pilot_tkoff_alt_m = 0.0;
  double pilot_speed_up_m_s = 0.0;
  double pilot_speed_dn_m_s = 0.0;
};

// How a parameter is stored, as ArduPilot declares it: integers keep the whole part of a value set,
// and MAVLink reports the type in PARAM_VALUE's param_type (the value still travels as a float).
enum class ParamKind { kFloat, kInt8, kInt16, kInt32 };

// The whole part an integer parameter keeps of value (value itself for kFloat). Thread-safe (pure).
double stored_value(ParamKind kind, double value);

// One parameter as the documentation lists it: name, accepted range, and its default on a vehicle whose
// battery holds battery_capacity_mah (BATT_CAPACITY and BATT_LOW_MAH follow the airframe).
struct ParamInfo {
  std::string name;
  double min = 0.0;
  double max = 0.0;
  double default_value = 0.0;
  ParamKind kind = ParamKind::kFloat;
};
// Every parameter in table order (the MAVLink param_index). Thread-safe (pure).
std::vector<ParamInfo> param_info(double battery_capacity_mah);

class ParamTable {
 public:
  // Defaults, with BATT_CAPACITY from the airframe (and BATT_LOW_MAH at 20 % of it).
  explicit ParamTable(double battery_capacity_mah);

  // The value of a named parameter; std::nullopt if the name is unknown. Linear scan: not hot path.
  std::optional<double> get(std::string_view name) const;
  // How a named parameter is stored; std::nullopt if the name is unknown.
  std::optional<ParamKind> kind(std::string_view name) const;
  // Sets a parameter and re-derives the SI values (an integer parameter keeps the whole part:
  // stored_value); false for an unknown name, a non-finite value or one outside the parameter's
  // documented range.
  bool set(std::string_view name, double value);
  // Names in table order (the MAVLink param_index).
  const std::vector<std::string>& names() const { return names_; }

  const ParamValues& values() const { return values_; }
  const DerivedParams& derived() const { return derived_; }

 private:
  void derive();

  ParamValues values_;
  DerivedParams derived_;
  std::vector<std::string> names_;
};

}  // namespace uavsim::server::fc
