// The mixer: seed eq. 4.1-4.5 generalised to any rotor layout. The allocation matrix A maps
// per-rotor thrusts to (roll, pitch, yaw torque about the centre of mass, collective thrust); the
// mixer applies its pseudo-inverse B = A^T (A A^T)^-1 and then desaturates with a fixed priority:
//   1. roll/pitch torque is kept whole if any collective thrust can carry it, else scaled down;
//   2. yaw torque is then scaled down to fit beside roll/pitch and the demanded collective, but
//      keeps up to a fixed share of each rotor's range (yaw headroom, as ArduCopter's
//      MOT_YAW_HEADROOM) even where that costs thrust;
//   3. collective thrust is then moved (up or down) into the range that fits the torques.
// So a vehicle near full or zero throttle keeps its attitude and gives up a fast turn before climb
// rate: a turn demanding full yaw torque once took the thrust of a climb and sank the vehicle.
// Motor command = sqrt(thrust / max_thrust), the inverse of the plant's square law.
//
// A degraded mixer leaves one (lost) rotor out. On a hexa with alternating spin the rotor opposite
// the lost one can then only push yaw one way, so yaw is no longer a controlled axis: roll/pitch
// come first, then thrust (held within what the live rotors give at zero torque), and yaw gets
// whatever torque keeps every live rotor in range, as close to the demand as that allows.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstddef>

#include "airframe/airframe.hpp"

namespace uavsim::server::fc {

inline constexpr std::size_t kMaxRotors = 12;

// What the mixer had to give up, for anti-windup and the land detector.
struct MixerStatus {
  double roll_pitch_scale = 1.0;   // fraction of the demanded roll/pitch torque delivered
  double yaw_scale = 1.0;          // fraction of the demanded yaw torque delivered
  double thrust_n = 0.0;           // collective thrust delivered
  bool limit_thrust_up = false;    // thrust lowered to fit the torques
  bool limit_thrust_down = false;  // thrust raised to fit the torques (or demand below zero)
};

class Mixer {
 public:
  // Builds A and B from the rotor layout. Throws std::invalid_argument (a config error) for no
  // rotors, more than kMaxRotors, or a layout that cannot control roll, pitch, yaw and thrust
  // independently.
  explicit Mixer(const airframe::AirframeParams& airframe);
  // The degraded mixer for the same airframe with rotor lost_rotor left out (its command is always
  // 0). Falls back to roll, pitch and thrust only where the live rotors cannot also set yaw. Throws
  // std::invalid_argument when they cannot even control roll, pitch and thrust.
  Mixer(const airframe::AirframeParams& airframe, std::size_t lost_rotor);

  // (torque_body_nm about the CoM, collective thrust_n) => per-rotor thrust_n and motor command [0,
  // 1]. Writes rotor_count() values to each output; no allocation.
  MixerStatus mix(const Eigen::Vector3d& torque_body_nm, double thrust_n, double* rotor_thrust_n,
                  double* motor_cmd) const;

  std::size_t rotor_count() const { return n_; }
  bool degraded() const { return degraded_; }
  double max_total_thrust_n() const { return max_total_thrust_n_; }
  // Row r of A: the effect of each rotor's thrust on roll (0), pitch (1), yaw (2), thrust (3).
  const Eigen::Matrix<double, 4, Eigen::Dynamic>& allocation() const { return a_; }

 private:
  void build(const airframe::AirframeParams& airframe, std::size_t lost_rotor);
  MixerStatus mix_degraded(const Eigen::Vector3d& torque_body_nm, double thrust_n,
                           double* rotor_thrust_n, double* motor_cmd) const;

  std::size_t n_ = 0;
  bool degraded_ = false;
  double max_total_thrust_n_ = 0.0;
  // degraded: the largest collective the live rotors give with zero torque
  double max_live_thrust_n_ = 0.0;
  Eigen::Matrix<double, 4, Eigen::Dynamic> a_;
  // B's columns per rotor, and max thrust, in fixed arrays for the hot path
  std::array<double, kMaxRotors> b_roll_{}, b_pitch_{}, b_yaw_{}, b_thrust_{}, max_thrust_n_{};
};

}  // namespace uavsim::server::fc
