// Applies the gimbal pointing a ground station commands over MAVLink (MAV_CMD_DO_MOUNT_CONTROL,
// MAV_CMD_DO_GIMBAL_MANAGER_PITCHYAW, GIMBAL_MANAGER_SET_PITCHYAW, MOUNT modes; stored by the endpoint in
// mavlink::GimbalState) to the vehicle's camera gimbals (objects::Gimbal). A gimbal keeps the world's
// stabilised mode ("down", "forward") until the first MAVLink command for its vehicle; each new command
// (a new GimbalState stamp) then sets it:
//   MAV_MOUNT_MODE_MAVLINK_TARGETING (2) and the other targeting modes: "targets" at the commanded pitch
//     (up positive) and yaw (MAVLink: clockwise positive, relative to the heading unless yaw_earth_frame,
//     then a heading from north that is held while the vehicle turns)
//   MAV_MOUNT_MODE_RETRACT (0), MAV_MOUNT_MODE_NEUTRAL (1): level, straight ahead ("forward")
// The API's gimbal op still works in between: only a new MAVLink command overrides it.
#pragma once

#include <functional>
#include <optional>
#include <vector>

#include "mavlink/gimbal_state.hpp"
#include "objects/gimbal.hpp"
#include "sim/simulation.hpp"

namespace uavsim::server::app {

// What a vehicle's gimbal device measures of its camera (its first gimbal in the world): the
// orientation the camera body has now, its stabilisation loop's lag included, in the gimbal
// protocol's vehicle frame (roll and pitch relative to the horizon, yaw relative to the vehicle's
// heading; a real device has these from its IMU and joint encoders, so they carry no compass
// error). nullopt: the vehicle has no gimbal. Loop thread.
std::optional<mavlink::GimbalDeviceAttitude> gimbal_device_attitude(
    const objects::GimbalSet& gimbals, sim::Simulation& sim, size_t vehicle);

// Points one gimbal as `state` asks, for a vehicle heading (ENU yaw, counter-clockwise from east).
void apply_gimbal_state(const mavlink::GimbalState& state, double vehicle_yaw_enu_rad, objects::Gimbal* gimbal);

class MavlinkGimbalBridge {
 public:
  // state_of(vehicle): the endpoint's GimbalState (MavlinkServer::gimbal). Loop thread.
  using StateOf = std::function<const mavlink::GimbalState&(size_t vehicle)>;
  MavlinkGimbalBridge(objects::GimbalSet& gimbals, StateOf state_of);
  // Every control step (a control observer). Loop thread.
  void update(sim::Simulation& sim);

 private:
  objects::GimbalSet& gimbals_;
  StateOf state_of_;
  std::vector<double> applied_stamp_;  // per gimbal: stamp of the MAVLink command applied last
};

}  // namespace uavsim::server::app
