// Airframe: the physical model of a multirotor that is not MuJoCo's job — rotor layout, first-order motor
// dynamics, rotor thrust/torque, aerodynamic drag and the battery (seed eq. 4.6–4.9).
// A pure library: plain structs and Eigen, no MuJoCo, no clocks, no I/O. The physics adapter loads
// AirframeParams from MJCF and writes the wrench returned here into the free joint's qfrc_applied dofs.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>
#include <vector>

namespace uavsim::server::airframe {

// One rotor, as described by a site in the vehicle's MJCF (see models/README.md).
struct RotorParams {
  Eigen::Vector3d position_body_m = Eigen::Vector3d::Zero();  // from the body origin, FLU
  // +1: the propeller turns counter-clockwise seen from above (its reaction torque on the body is -z),
  // -1: clockwise (reaction torque +z).
  int spin_dir = 1;
  double max_thrust_n = 0.0;    // thrust at full command
  double torque_coef_m = 0.0;   // reaction torque = torque_coef_m * thrust_n
  double time_const_s = 0.02;   // first-order lag of rotor speed
  double prop_diameter_m = 0.25;  // for the momentum-theory power of seed eq. 4.6
};

// 3S LiPo battery (seed eq. 4.6–4.9).
struct BatteryParams {
  double capacity_mah = 5000.0;
  double voltage_full_v = 12.6;
  double voltage_nominal_v = 11.1;  // eq. 4.9 divides power by this
  double voltage_empty_v = 10.5;
  double control_power_w = 5.0;     // flight controller, companion computer, radios
  double prop_efficiency = 0.7;     // eta_1 of eq. 4.7
  double motor_efficiency = 0.75;   // eta_2 of eq. 4.7
  // Internal resistance of the pack (field conditions): the terminal voltage sags by I R under load and
  // the rotors' top speed, hence their thrust, follows it (battery_thrust_scale). 0: no sag, thrust
  // independent of the voltage (the ideal world).
  double internal_resistance_ohm = 0.0;
};

// Immutable description of one vehicle type, loaded once from MJCF.
struct AirframeParams {
  std::string frame;          // "quad", "hexa", ...
  double mass_kg = 0.0;       // total, from MuJoCo's body masses
  Eigen::Matrix3d inertia_body_kgm2 = Eigen::Matrix3d::Identity();
  Eigen::Vector3d com_body_m = Eigen::Vector3d::Zero();  // centre of mass relative to the body origin
  std::vector<RotorParams> rotors;
  // drag force in the body frame, per axis: F = -(lin * v + quad * |v| * v)
  Eigen::Vector3d drag_lin_n_per_m_s = Eigen::Vector3d::Zero();
  Eigen::Vector3d drag_quad_n_per_m2_s2 = Eigen::Vector3d::Zero();
  BatteryParams battery;

  double max_total_thrust_n() const;
};

// Mutable per-vehicle plant state.
struct MotorState {
  // normalised rotor speed in [0, 1]; thrust = max_thrust * speed^2
  std::vector<double> speed;
  std::vector<bool> failed;  // a failed motor produces no thrust whatever its command
};

struct BatteryState {
  double consumed_mah = 0.0;
  double current_a = 0.0;
  double voltage_v = 12.6;
};

// Generalised force on a free body about its origin: world-frame force, body-frame torque.
struct Wrench {
  Eigen::Vector3d force_enu_n = Eigen::Vector3d::Zero();
  Eigen::Vector3d torque_body_nm = Eigen::Vector3d::Zero();
};

MotorState make_motor_state(const AirframeParams& params);

// Charge left, in [0, 1].
double battery_remaining(const AirframeParams& params, const BatteryState& state);

// (motor_cmd in [0,1], motor state) => motor state after dt; first-order lag per rotor.
void step_motors(const AirframeParams& params, const double* motor_cmd, double dt_s,
                 MotorState* state);

// The per-rotor factor 1 - exp(-dt/tau) of the exact first-order discretisation, for a fixed dt.
std::vector<double> motor_lag_alpha(const AirframeParams& params, double dt_s);
// step_motors with the factors precomputed (the hot path: no exp per step).
void step_motors_alpha(const AirframeParams& params, const double* motor_cmd, const double* lag_alpha,
                       MotorState* state);

// Per-rotor thrust from the current rotor speeds; writes params.rotors.size() values.
void rotor_thrusts(const AirframeParams& params, const MotorState& state, double* thrust_n);

// (rotor thrusts, attitude, velocity) => wrench about the body origin: rotor thrust along body +z,
// rotor reaction torques, and body-frame drag applied at the centre of mass.
Wrench compute_wrench(const AirframeParams& params, const double* thrust_n,
                      const Eigen::Quaterniond& q_enu_body, const Eigen::Vector3d& velocity_enu_m_s);

// (rotor thrusts, dt) => battery state: momentum-theory power (eq. 4.6) / efficiencies (eq. 4.7)
// + control power (eq. 4.8), current at nominal voltage (eq. 4.9), a linear voltage sag with charge.
// With an internal resistance R the open-circuit voltage V_oc (linear in charge) sags under the load P:
// V = (V_oc + sqrt(V_oc^2 - 4 R P)) / 2 (from V = V_oc - R I, I = P / V), and I = P / V.
void step_battery(const AirframeParams& params, const double* thrust_n, double dt_s,
                  BatteryState* state);

// The fraction of rated thrust the rotors can make at the battery's terminal voltage: rotor speed at a
// given command scales with the voltage and thrust with its square, (V / V_full)^2. Exactly 1 when the
// pack has no internal resistance (the ideal world keeps thrust independent of the battery).
double battery_thrust_scale(const AirframeParams& params, const BatteryState& state);

}  // namespace uavsim::server::airframe
