#include "airframe/airframe.hpp"
#include "uavsim/common/angles.hpp"

#include <algorithm>
#include <cmath>

namespace uavsim::server::airframe {

namespace {
constexpr double kAirDensityKgM3 = 1.225;  // ISA sea level, as in seed eq. 4.6
using common::kPi;
}  // namespace

double AirframeParams::max_total_thrust_n() const {
  double total = 0.0;
  for (const RotorParams& r : rotors) total += r.max_thrust_n;
  return total;
}


double battery_remaining(const AirframeParams& params, const BatteryState& state) {
  return std::clamp(1.0 - state.consumed_mah / params.battery.capacity_mah, 0.0, 1.0);
}

MotorState make_motor_state(const AirframeParams& params) {
  MotorState s;
  s.speed.assign(params.rotors.size(), 0.0);
  s.failed.assign(params.rotors.size(), false);
  return s;
}

std::vector<double> motor_lag_alpha(const AirframeParams& params, double dt_s) {
  std::vector<double> alpha;
  for (const RotorParams& r : params.rotors) {
    alpha.push_back(1.0 - std::exp(-dt_s / std::max(r.time_const_s, 1e-4)));
  }
  return alpha;
}

void step_motors_alpha(const AirframeParams& params, const double* motor_cmd, const double* lag_alpha,
                       MotorState* state) {
  for (size_t k = 0; k < params.rotors.size(); ++k) {
    // clamp the command to [0, 1]; a failed motor is commanded to 0
    const double cmd = state->failed[k] ? 0.0 : std::clamp(motor_cmd[k], 0.0, 1.0);
    // exact discretisation of the first-order lag: s += (cmd - s) * (1 - exp(-dt/tau))
    state->speed[k] += (cmd - state->speed[k]) * lag_alpha[k];
  }
}

void step_motors(const AirframeParams& params, const double* motor_cmd, double dt_s,
                 MotorState* state) {
  const std::vector<double> alpha = motor_lag_alpha(params, dt_s);
  step_motors_alpha(params, motor_cmd, alpha.data(), state);
}

void rotor_thrusts(const AirframeParams& params, const MotorState& state, double* thrust_n) {
  // thrust grows with the square of rotor speed
  for (size_t k = 0; k < params.rotors.size(); ++k) {
    const double s = state.speed[k];
    thrust_n[k] = params.rotors[k].max_thrust_n * s * s;
  }
}

Wrench compute_wrench(const AirframeParams& params, const double* thrust_n,
                      const Eigen::Quaterniond& q_enu_body,
                      const Eigen::Vector3d& velocity_enu_m_s) {
  // rotor thrust along body +z, its moment about the body origin, and the reaction torque about z
  Eigen::Vector3d force_body = Eigen::Vector3d::Zero();
  Eigen::Vector3d torque_body = Eigen::Vector3d::Zero();
  for (size_t k = 0; k < params.rotors.size(); ++k) {
    const RotorParams& r = params.rotors[k];
    const Eigen::Vector3d f(0.0, 0.0, thrust_n[k]);
    force_body += f;
    torque_body += r.position_body_m.cross(f);
    // a counter-clockwise propeller (spin_dir +1) pushes the body clockwise: torque -z
    torque_body.z() -= r.spin_dir * r.torque_coef_m * thrust_n[k];
  }

  // drag in the body frame, applied at the centre of mass: F = -(lin * v + quad * |v| * v) per axis
  const Eigen::Matrix3d R_enu_body = q_enu_body.toRotationMatrix();
  const Eigen::Vector3d v_body = R_enu_body.transpose() * velocity_enu_m_s;
  const Eigen::Vector3d drag_body =
      -(params.drag_lin_n_per_m_s.cwiseProduct(v_body) +
        params.drag_quad_n_per_m2_s2.cwiseProduct(v_body.cwiseAbs().cwiseProduct(v_body)));
  force_body += drag_body;
  torque_body += params.com_body_m.cross(drag_body);

  Wrench w;
  w.force_enu_n = R_enu_body * force_body;
  w.torque_body_nm = torque_body;
  return w;
}

void step_battery(const AirframeParams& params, const double* thrust_n, double dt_s,
                  BatteryState* state) {
  const BatteryParams& b = params.battery;
  // eq. 4.6: momentum-theory hover power per rotor, P = T^1.5 / sqrt(2 rho A)
  double power_w = 0.0;
  for (size_t k = 0; k < params.rotors.size(); ++k) {
    const double d = params.rotors[k].prop_diameter_m;
    const double area_m2 = kPi / 4.0 * d * d;
    const double t = std::max(thrust_n[k], 0.0);
    power_w += t * std::sqrt(t) / std::sqrt(2.0 * kAirDensityKgM3 * area_m2);
  }
  // eq. 4.7: electrical power through propeller and motor efficiency; eq. 4.8: plus the electronics
  power_w = power_w / (b.prop_efficiency * b.motor_efficiency) + b.control_power_w;
  if (b.internal_resistance_ohm <= 0.0) {
    // eq. 4.9: current at the nominal 3S voltage
    state->current_a = power_w / b.voltage_nominal_v;
    state->consumed_mah += state->current_a * dt_s * (1000.0 / 3600.0);
    // voltage falls linearly from full to empty with the charge drawn
    const double used = std::clamp(state->consumed_mah / b.capacity_mah, 0.0, 1.0);
    state->voltage_v = b.voltage_full_v - (b.voltage_full_v - b.voltage_empty_v) * used;
    return;
  }
  // sag: open-circuit voltage from the charge drawn, terminal voltage V = V_oc - R P / V (the larger
  // root; past the pack's maximum power V_oc^2 / 4R it is held at V_oc / 2)
  const double used = std::clamp(state->consumed_mah / b.capacity_mah, 0.0, 1.0);
  const double v_oc = b.voltage_full_v - (b.voltage_full_v - b.voltage_empty_v) * used;
  const double disc = std::max(0.0, v_oc * v_oc - 4.0 * b.internal_resistance_ohm * power_w);
  state->voltage_v = 0.5 * (v_oc + std::sqrt(disc));
  state->current_a = power_w / state->voltage_v;
  state->consumed_mah += state->current_a * dt_s * (1000.0 / 3600.0);
}

double battery_thrust_scale(const AirframeParams& params, const BatteryState& state) {
  if (params.battery.internal_resistance_ohm <= 0.0) return 1.0;
  const double r = std::clamp(state.voltage_v / params.battery.voltage_full_v, 0.0, 1.0);
  return r * r;
}

}  // namespace uavsim::server::airframe
