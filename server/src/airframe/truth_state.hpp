// The ground truth of a rigid body: what physics measures of a vehicle each step and hands to the
// flight controller's sensor models (fc::TruthState names the same type), the gimbals, the trucks
// and the radio. It lives beside the airframe, below both physics and fc, so physics hands it out
// without depending on the flight controller.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace uavsim::server::airframe {

struct TruthState {
  Eigen::Vector3d position_enu_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d velocity_enu_m_s = Eigen::Vector3d::Zero();
  Eigen::Quaterniond q_enu_body = Eigen::Quaterniond::Identity();
  Eigen::Vector3d rate_body_rad_s = Eigen::Vector3d::Zero();
  Eigen::Vector3d accel_enu_m_s2 = Eigen::Vector3d::Zero();  // kinematic acceleration (no gravity)
  bool on_ground = true;  // a contact between the vehicle and the ground or a deck
};

}  // namespace uavsim::server::airframe
