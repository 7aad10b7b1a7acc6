// The pointing a ground station last commanded for a vehicle's camera gimbal (MAV_CMD_DO_MOUNT_CONTROL,
// MAV_CMD_DO_GIMBAL_MANAGER_PITCHYAW, GIMBAL_MANAGER_SET_PITCHYAW). The MAVLink endpoint writes it on the
// loop thread; the camera renderer reads it there through MavlinkServer::gimbal(vehicle).
#pragma once

#include <cstdint>

#include "uavsim/common/mavlink/generated/enums.hpp"

namespace uavsim::server::mavlink {

struct GimbalState {
  double pitch_deg = 0.0;  // positive up (MAVLink), 0 = level, -90 = straight down
  double roll_deg = 0.0;
  double yaw_deg = 0.0;    // relative to the vehicle's heading unless yaw_earth_frame; positive clockwise
  bool yaw_earth_frame = false;          // yaw is a heading (0 = north) instead of relative to the body
  double pitch_rate_deg_s = 0.0;         // rate commands (NaN-free; 0 when not given)
  double yaw_rate_deg_s = 0.0;
  std::uint8_t mount_mode =  // MAV_MOUNT_MODE
      common::mavlink::to_underlying(common::mavlink::MavMountMode::MavlinkTargeting);
  double stamp_s = -1.0;                 // sim time of the last command; < 0: never commanded
};

// What a gimbal device measures of its camera (its IMU and joint encoders) and reports in
// GIMBAL_DEVICE_ATTITUDE_STATUS: the attitude of the camera (FRD, x along the optical axis) in the
// gimbal protocol's vehicle frame, NED turned by the vehicle's heading. So roll and pitch are
// relative to the horizon and yaw to the vehicle's heading: a device knows these without a compass
// (gravity, encoders). Tait-Bryan z-y'-x'' angles, as in ATTITUDE.
struct GimbalDeviceAttitude {
  double roll_deg = 0.0;   // positive: rolled to the right
  double pitch_deg = 0.0;  // positive up
  double yaw_deg = 0.0;    // relative to the vehicle's heading, positive clockwise
};

}  // namespace uavsim::server::mavlink
