// Airframes built in code for the fc tests: a 550 mm quad and a DJI S900-class hexa.
#pragma once

#include <cmath>

#include "airframe/airframe.hpp"
#include "fc/angles.hpp"

namespace uavsim::server::fc::test {

inline constexpr double kTestGravity = 9.80665;

// Quad X, 550 mm motor-to-motor: arms of 0.275 m at 45 degrees, ArduPilot motor order
// (1 front-right CCW, 2 back-left CCW, 3 front-left CW, 4 back-right CW).
// max thrust per rotor: 2 * m g / 4 = 2 * 1.5 * 9.80665 / 4 = 7.355 N.
inline airframe::AirframeParams make_quad() {
  airframe::AirframeParams a;
  a.frame = "quad";
  a.mass_kg = 1.5;
  a.inertia_body_kgm2 = Eigen::Vector3d(0.029, 0.029, 0.055).asDiagonal();
  const double r = 0.275 / std::sqrt(2.0);
  const double xs[4] = {r, -r, r, -r};
  const double ys[4] = {-r, r, r, -r};
  const int dirs[4] = {1, 1, -1, -1};
  for (int k = 0; k < 4; ++k) {
    airframe::RotorParams rp;
    rp.position_body_m = Eigen::Vector3d(xs[k], ys[k], 0.0);
    rp.spin_dir = dirs[k];
    rp.max_thrust_n = 2.0 * a.mass_kg * kTestGravity / 4.0;
    rp.torque_coef_m = 0.016;
    rp.time_const_s = 0.03;
    rp.prop_diameter_m = 0.254;
    a.rotors.push_back(rp);
  }
  a.drag_lin_n_per_m_s = Eigen::Vector3d::Constant(0.1);
  a.drag_quad_n_per_m2_s2 = Eigen::Vector3d::Constant(0.05);
  a.battery.capacity_mah = 5000.0;
  return a;
}

// Hexa X (S900 class): 6 rotors on a 0.45 m radius at 30 + 60 k degrees, alternating spin,
// 6.8 kg; max thrust per rotor 2 * 6.8 * 9.80665 / 6 = 22.23 N.
inline airframe::AirframeParams make_hexa() {
  airframe::AirframeParams a;
  a.frame = "hexa";
  a.mass_kg = 6.8;
  a.inertia_body_kgm2 = Eigen::Vector3d(0.35, 0.35, 0.62).asDiagonal();
  for (int k = 0; k < 6; ++k) {
    const double ang = (30.0 + 60.0 * k) * kPi / 180.0;
    airframe::RotorParams rp;
    rp.position_body_m = Eigen::Vector3d(0.45 * std::cos(ang), 0.45 * std::sin(ang), 0.0);
    rp.spin_dir = (k % 2 == 0) ? 1 : -1;
    rp.max_thrust_n = 2.0 * a.mass_kg * kTestGravity / 6.0;
    rp.torque_coef_m = 0.02;
    rp.time_const_s = 0.04;
    rp.prop_diameter_m = 0.38;
    a.rotors.push_back(rp);
  }
  a.drag_lin_n_per_m_s = Eigen::Vector3d::Constant(0.3);
  a.drag_quad_n_per_m2_s2 = Eigen::Vector3d::Constant(0.15);
  a.battery.capacity_mah = 16000.0;
  return a;
}

}  // namespace uavsim::server::fc::test
