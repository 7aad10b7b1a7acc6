// A test-only 6-DOF rigid-body plant for closed-loop fc tests: the airframe library's motors, thrust,
// wrench and battery, integrated semi-implicitly at the plant rate, on flat ground at z = 0 with a
// contact that supports the vehicle (no bounce, no sliding, sits level) while thrust < weight.
#pragma once

#include <Eigen/Dense>
#include <cstdint>
#include <vector>

#include "airframe/airframe.hpp"
#include "fc/fc_types.hpp"
#include "fc/flight_controller.hpp"

namespace uavsim::server::fc::test {

class RigidBodyPlant {
 public:
  explicit RigidBodyPlant(const airframe::AirframeParams& params)
      : params_(params), motors_(airframe::make_motor_state(params)),
        thrust_n_(params.rotors.size(), 0.0) {
    truth_.on_ground = true;
  }

  // (motor commands, dt) => truth after dt
  void step(const double* motor_cmd, double dt_s) {
    airframe::step_motors(params_, motor_cmd, dt_s, &motors_);
    airframe::rotor_thrusts(params_, motors_, thrust_n_.data());
    airframe::step_battery(params_, thrust_n_.data(), dt_s, &battery_);
    const airframe::Wrench w =
        airframe::compute_wrench(params_, thrust_n_.data(), truth_.q_enu_body, truth_.velocity_enu_m_s);
    // translational: a = F/m - g
    Eigen::Vector3d a = w.force_enu_n / params_.mass_kg - Eigen::Vector3d(0.0, 0.0, kG);
    // rotational: J w_dot = tau - w x J w
    const Eigen::Matrix3d& J = params_.inertia_body_kgm2;
    Eigen::Vector3d& wb = truth_.rate_body_rad_s;
    const Eigen::Vector3d w_dot = J.ldlt().solve(w.torque_body_nm - wb.cross(J * wb));
    const bool resting = truth_.position_enu_m.z() <= 0.0 && a.z() <= 0.0;
    if (resting) {
      // ground contact: supported, held by friction, sits level keeping its heading
      a.setZero();
      truth_.velocity_enu_m_s.setZero();
      wb.setZero();
      const Eigen::Vector3d x = truth_.q_enu_body * Eigen::Vector3d::UnitX();
      truth_.q_enu_body = Eigen::Quaterniond(Eigen::AngleAxisd(std::atan2(x.y(), x.x()), Eigen::Vector3d::UnitZ()));
      truth_.position_enu_m.z() = 0.0;
    } else {
      truth_.velocity_enu_m_s += a * dt_s;
      truth_.position_enu_m += truth_.velocity_enu_m_s * dt_s;
      wb += w_dot * dt_s;
      const double ang = wb.norm() * dt_s;
      if (ang > 0.0) {
        truth_.q_enu_body = (truth_.q_enu_body * Eigen::Quaterniond(Eigen::AngleAxisd(ang, wb.normalized()))).normalized();
      }
      if (truth_.position_enu_m.z() < 0.0) {
        // touchdown: stop on the ground within this step; the accelerometer sees the impulse
        a = -truth_.velocity_enu_m_s / dt_s;
        truth_.position_enu_m.z() = 0.0;
        truth_.velocity_enu_m_s.setZero();
      }
    }
    truth_.accel_enu_m_s2 = a;
    truth_.on_ground = truth_.position_enu_m.z() <= 0.0;
  }

  const TruthState& truth() const { return truth_; }
  TruthState& mutable_truth() { return truth_; }
  const airframe::BatteryState& battery() const { return battery_; }
  airframe::BatteryState& mutable_battery() { return battery_; }
  airframe::MotorState& motors() { return motors_; }

 private:
  static constexpr double kG = 9.80665;
  airframe::AirframeParams params_;
  airframe::MotorState motors_;
  airframe::BatteryState battery_;
  TruthState truth_;
  std::vector<double> thrust_n_;
};

// The plant at 1 kHz and the FC at 500 Hz, with time in integer microseconds so nothing drifts.
class Sim {
 public:
  static constexpr int64_t kPlantStepUs = 1000;
  static constexpr int kFcEvery = 2;

  Sim(const airframe::AirframeParams& params, uint64_t seed)
      : plant(params), fc(params, seed), cmd_(params.rotors.size(), 0.0) {}

  double time_s() const { return static_cast<double>(time_us_) * 1e-6; }

  // Steps the plant once (and the FC when due); optional GCS heartbeat at 1 Hz.
  void step() {
    if (step_count_ % kFcEvery == 0) {
      if (gcs_heartbeats && time_us_ % 1000000 == 0) fc.on_gcs_heartbeat(time_s());
      fc.update(time_s(), plant.truth(), plant.battery(), cmd_.data());
    }
    plant.step(cmd_.data(), static_cast<double>(kPlantStepUs) * 1e-6);
    time_us_ += kPlantStepUs;
    ++step_count_;
  }

  void run_for(double seconds) {
    const int64_t end = time_us_ + static_cast<int64_t>(seconds * 1e6 + 0.5);
    while (time_us_ < end) step();
  }

  // Runs until pred() or the timeout; true if pred() held.
  template <typename Pred>
  bool run_until(Pred pred, double timeout_s) {
    const int64_t end = time_us_ + static_cast<int64_t>(timeout_s * 1e6 + 0.5);
    while (time_us_ < end) {
      step();
      if (step_count_ % kFcEvery == 0 && pred()) return true;
    }
    return false;
  }

  const Eigen::Vector3d& pos() const { return plant.truth().position_enu_m; }

  RigidBodyPlant plant;
  FlightController fc;
  bool gcs_heartbeats = false;

 private:
  std::vector<double> cmd_;
  int64_t time_us_ = 0;
  int64_t step_count_ = 0;
};

}  // namespace uavsim::server::fc::test
