#include "coverage_config.hpp"

#include <algorithm>
#include <cmath>
#include <string>

namespace uavsim::missions::coverage {

namespace {

// "" if lo <= v <= hi (and finite), else the message
std::string check(const char* name, double v, double lo, double hi) {
  if (std::isfinite(v) && v >= lo && v <= hi) return "";
  return std::string(name) + " = " + std::to_string(v) + " is outside [" + std::to_string(lo) +
         ", " + std::to_string(hi) + "]";
}

}  // namespace

std::string CoverageConfig::validate() const {
  const FlockGains& g = gains;
  for (const std::string& e : {
           check("origin_x_m", origin_x_m, -1e5, 1e5),
           check("origin_y_m", origin_y_m, -1e5, 1e5),
           // positions travel over the radio as 0.1 m in 16 bits
           check("length_x_m", length_x_m, 1.0, 3000.0),
           check("width_y_m", width_y_m, 1.0, 3000.0),
           check("x_sensor_m", x_sensor_m, 0.5, 200.0),
           check("y_sensor_m", y_sensor_m, 0.5, 200.0),
           check("altitude_m", altitude_m, 2.0, 500.0),
           check("altitude_tolerance_m", altitude_tolerance_m, 0.05, 50.0),
           check("heading_tolerance_rad", heading_tolerance_rad, 0.001, 0.7),
           check("stripe_fill", stripe_fill, 0.3, 0.99),
           check("gains.d_r1_m", g.d_r1_m, 0.5, 200.0),
           check("gains.c_p_r1", g.c_p_r1, 0.0, 100.0),
           check("gains.c_o_r1", g.c_o_r1, 0.0, 100.0),
           check("gains.d_r1", g.d_r1, 0.01, 10.0),
           check("gains.s_r1_m_s", g.s_r1_m_s, 0.0, 20.0),
           check("gains.kp_r2", g.kp_r2, 0.0, 100.0),
           check("gains.s_r2_deg_s", g.s_r2_deg_s, 0.0, 720.0),
           check("gains.kp_r3x", g.kp_r3x, 0.0, 100.0),
           check("gains.ki_r3x", g.ki_r3x, 0.0, 100.0),
           check("gains.s_r3x_m_s", g.s_r3x_m_s, 0.0, 20.0),
           check("gains.kp_r3y", g.kp_r3y, 0.0, 100.0),
           check("gains.s_r3y_m_s", g.s_r3y_m_s, 0.0, 20.0),
           check("gains.kp_close_gap", g.kp_close_gap, 0.0, 100.0),
           check("gains.s_close_gap_m_s", g.s_close_gap_m_s, 0.0, 20.0),
           check("gains.close_gap_leader_speed_m_s", g.close_gap_leader_speed_m_s, 0.0, 50.0),
           check("broadcast_hz", broadcast_hz, 0.5, 50.0),
           check("max_age_base_s", max_age_base_s, 0.1, 60.0),
           check("max_age_per_hop_s", max_age_per_hop_s, 0.0, 60.0),
           check("query_retransmit_s", query_retransmit_s, 0.02, 10.0),
           check("cruise_speed_m_s", cruise_speed_m_s, 0.5, 20.0),
           check("deploy_speed_m_s", deploy_speed_m_s, 0.5, 30.0),
           check("edge_margin_fraction", edge_margin_fraction, 0.0, 0.9),
           check("lateral_threshold_m", lateral_threshold_m, 0.5, 1e4),
           check("smoothing_half_window", smoothing_half_window, 0, 50),
           check("formation_tolerance_m", formation_tolerance_m, 0.1, 100.0),
           check("deploy_timeout_s", deploy_timeout_s, 1.0, 3600.0),
           check("home_layers", home_layers, 1, 20),
           check("home_layer_m", home_layer_m, 0.0, 50.0),
           check("home_speed_m_s", home_speed_m_s, 0.5, 30.0),
           check("max_speed_m_s", max_speed_m_s, 0.5, 30.0),
       }) {
    if (!e.empty()) return e;
  }
  if (stripe_count() > 4096) return "too many stripes (length_x_m / x_sensor_m over 4096)";
  return "";
}

int CoverageConfig::stripe_count() const {
  return std::max(1, static_cast<int>(std::ceil(length_x_m / (stripe_fill * x_sensor_m) - 1e-9)));
}

double CoverageConfig::stripe_height_m() const { return length_x_m / stripe_count(); }

}  // namespace uavsim::missions::coverage
