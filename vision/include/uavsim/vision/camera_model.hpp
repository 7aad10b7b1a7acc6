// Pinhole camera model and camera poses in the world (ENU) frame.
//
// Frames (docs/development.md, "Code conventions"): `cam` is the OpenCV convention (x right, y
// down, z forward); `enu` is the MuJoCo world (z up); `body` is FLU. Pixel coordinates follow
// OpenCV: the centre of the top-left pixel is (0, 0), so the optical axis of a centred camera is at
// ((width - 1) / 2, (height - 1) / 2). All functions are pure and thread-safe.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <optional>

#include "uavsim/common/pinhole.hpp"

namespace uavsim::vision {

// The pinhole model the renderer draws with (common/pinhole.hpp): one model, so what vision projects is
// what was rendered.
using PinholeIntrinsics = common::PinholeIntrinsics;

// A camera's pose in the world: where its optical centre is and how its axes lie.
struct CameraPose {
  Eigen::Vector3d position_enu_m = Eigen::Vector3d::Zero();
  Eigen::Matrix3d R_enu_cam = Eigen::Matrix3d::Identity();

  Eigen::Vector3d cam_to_enu(const Eigen::Vector3d& p_cam_m) const;
  Eigen::Vector3d enu_to_cam(const Eigen::Vector3d& p_enu_m) const;
};

// Two-axis gimbal angles. pitch_rad is the elevation of the optical axis (MAVLink gimbal
// convention: 0 = forward, -pi/2 = straight down); yaw_rad turns the camera about the body's (or,
// when stabilised, the world's) up axis, positive to the left (counter-clockwise seen from above,
// as ENU yaw). earth_stabilised: the gimbal cancels the vehicle's roll and pitch (the seed's
// cameras were "programmed to always point down" / "always look forward", seed 7.1-7.2); otherwise
// the angles are body-relative.
struct GimbalAngles {
  double pitch_rad = 0.0;
  double yaw_rad = 0.0;
  bool earth_stabilised = true;
};

// Body attitude from roll, pitch, yaw for an FLU body in ENU (REP-103: R = Rz(yaw) Ry(pitch)
// Rx(roll); positive pitch is nose down, positive yaw is counter-clockwise from east).
Eigen::Quaterniond q_enu_body_from_rpy(double roll_rad, double pitch_rad, double yaw_rad);

// Fixed rotation from the OpenCV camera axes to a forward-looking FLU mount: the optical axis (cam
// z) is mount x, cam x (right) is -mount y, cam y (down) is -mount z.
Eigen::Matrix3d R_mount_cam();

// Pose of a camera on a gimbal at camera_offset_body_m from the vehicle's origin.
CameraPose camera_pose_from_vehicle(
    const Eigen::Vector3d& vehicle_position_enu_m, const Eigen::Quaterniond& q_enu_body,
    const GimbalAngles& gimbal,
    const Eigen::Vector3d& camera_offset_body_m = Eigen::Vector3d::Zero());

// Where a ray from the camera (unit or not, in the cam frame) meets the horizontal plane
// z_enu = plane_height_enu_m; nullopt if the ray is parallel to it or points away from it.
std::optional<Eigen::Vector3d> intersect_ray_with_plane(const CameraPose& pose,
                                                        const Eigen::Vector3d& ray_cam,
                                                        double plane_height_enu_m);

// Pixel -> point on the plane z_enu = plane_height_enu_m (the ground, or a truck deck) (seed 7.1:
// "the distance between the UAV and the marker could be inferred from the GPS altitude").
std::optional<Eigen::Vector3d> pixel_to_plane_enu(const PinholeIntrinsics& intrinsics,
                                                  const CameraPose& pose,
                                                  const Eigen::Vector2d& pixel_px,
                                                  double plane_height_enu_m);

}  // namespace uavsim::vision
