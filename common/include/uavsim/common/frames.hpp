// ENU <-> NED and FLU <-> FRD: the one file where the simulator's frames (world ENU, body FLU) meet
// MAVLink's (local NED, body FRD). Everything the server's endpoint and the client receive or send passes
// through here.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>

#include "uavsim/common/angles.hpp"

namespace uavsim::common::frames {

// Vectors: ENU (x east, y north, z up) <-> NED (x north, y east, z down). The map is its own inverse.
inline Eigen::Vector3d ned_from_enu(const Eigen::Vector3d& v_enu) { return {v_enu.y(), v_enu.x(), -v_enu.z()}; }
inline Eigen::Vector3d enu_from_ned(const Eigen::Vector3d& v_ned) { return {v_ned.y(), v_ned.x(), -v_ned.z()}; }

// Body vectors: FLU (forward, left, up) <-> FRD (forward, right, down).
inline Eigen::Vector3d frd_from_flu(const Eigen::Vector3d& v_flu) { return {v_flu.x(), -v_flu.y(), -v_flu.z()}; }
inline Eigen::Vector3d flu_from_frd(const Eigen::Vector3d& v_frd) { return {v_frd.x(), -v_frd.y(), -v_frd.z()}; }

// Rotations between the world frames and between the body frames.
inline Eigen::Quaterniond q_ned_enu() {
  Eigen::Matrix3d r;
  r << 0, 1, 0, 1, 0, 0, 0, 0, -1;
  return Eigen::Quaterniond(r);
}
inline Eigen::Quaterniond q_flu_frd() { return Eigen::Quaterniond(0.0, 1.0, 0.0, 0.0); }  // pi about x

// Attitude: q_enu_flu (maps FLU body vectors into ENU) <-> q_ned_frd (MAVLink's attitude quaternion).
inline Eigen::Quaterniond q_ned_frd_from_q_enu_flu(const Eigen::Quaterniond& q_enu_flu) {
  return (q_ned_enu() * q_enu_flu * q_flu_frd()).normalized();
}
inline Eigen::Quaterniond q_enu_flu_from_q_ned_frd(const Eigen::Quaterniond& q_ned_frd) {
  return (q_ned_enu().conjugate() * q_ned_frd * q_flu_frd().conjugate()).normalized();
}

// Heading: NED yaw (0 = north, clockwise) <-> ENU yaw (0 = east, counter-clockwise). Own inverse.
inline double yaw_ned_from_yaw_enu(double yaw_enu_rad) { return wrap_pi(kPi / 2.0 - yaw_enu_rad); }
inline double yaw_enu_from_yaw_ned(double yaw_ned_rad) { return wrap_pi(kPi / 2.0 - yaw_ned_rad); }

// Roll, pitch, yaw: the Tait-Bryan angles z-y'-x'' of a rotation, q = Rz(yaw) Ry(pitch) Rx(roll).
struct Euler {
  double roll_rad = 0.0;
  double pitch_rad = 0.0;
  double yaw_rad = 0.0;
};
inline Euler euler_zyx(const Eigen::Quaterniond& q) {
  const double w = q.w(), x = q.x(), y = q.y(), z = q.z();
  Euler e;
  e.roll_rad = std::atan2(2.0 * (w * x + y * z), 1.0 - 2.0 * (x * x + y * y));
  const double s = 2.0 * (w * y - z * x);
  e.pitch_rad = std::asin(s > 1.0 ? 1.0 : (s < -1.0 ? -1.0 : s));
  e.yaw_rad = std::atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z));
  return e;
}
// MAVLink's attitude (ATTITUDE): of q_ned_frd, yaw from north clockwise, pitch nose up.
inline Euler euler_from_q_ned_frd(const Eigen::Quaterniond& q_ned_frd) {
  return euler_zyx(q_ned_frd);
}
// The simulator's attitude: of q_enu_flu, yaw from east counter-clockwise, pitch about the left
// axis (nose down), roll about the forward axis (as the ground-truth records write it).
inline Euler euler_from_q_enu_flu(const Eigen::Quaterniond& q_enu_flu) {
  return euler_zyx(q_enu_flu);
}

// Rotates a horizontal NED vector given in a yaw-aligned body frame (MAV_FRAME_BODY_*) into NED.
inline Eigen::Vector3d ned_from_body_yaw(const Eigen::Vector3d& v, double yaw_ned_rad) {
  const double c = std::cos(yaw_ned_rad), s = std::sin(yaw_ned_rad);
  return {c * v.x() - s * v.y(), s * v.x() + c * v.y(), v.z()};
}

}  // namespace uavsim::common::frames
