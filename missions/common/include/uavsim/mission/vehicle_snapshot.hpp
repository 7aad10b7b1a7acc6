// What a mission's state machine reads of its own vehicle at each step, from the vehicle's MAVLink
// telemetry in the world's ENU frame. The coverage agent's and the MBZIRC 2020 UAV's inputs begin
// with it; each program fills it from client::Telemetry by its own rule for "on the ground".
#pragma once

#include <Eigen/Core>

namespace uavsim::mission {

struct VehicleSnapshot {
  bool armed = false;
  bool on_ground = true;
  Eigen::Vector3d position_enu_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d velocity_enu_m_s = Eigen::Vector3d::Zero();
  double yaw_enu_rad = 0.0;
};

}  // namespace uavsim::mission
