#include "uavsim/vision/camera_model.hpp"

#include <cmath>

namespace uavsim::vision {

Eigen::Vector3d CameraPose::cam_to_enu(const Eigen::Vector3d& p_cam_m) const {
  return position_enu_m + R_enu_cam * p_cam_m;
}

Eigen::Vector3d CameraPose::enu_to_cam(const Eigen::Vector3d& p_enu_m) const {
  return R_enu_cam.transpose() * (p_enu_m - position_enu_m);
}

Eigen::Quaterniond q_enu_body_from_rpy(double roll_rad, double pitch_rad, double yaw_rad) {
  return Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitZ()) *
         Eigen::AngleAxisd(pitch_rad, Eigen::Vector3d::UnitY()) *
         Eigen::AngleAxisd(roll_rad, Eigen::Vector3d::UnitX());
}

Eigen::Matrix3d R_mount_cam() {
  Eigen::Matrix3d r;
  // columns: cam x (right) = -y_mount, cam y (down) = -z_mount, cam z (forward) = x_mount
  r << 0, 0, 1,  //
      -1, 0, 0,  //
      0, -1, 0;
  return r;
}

CameraPose camera_pose_from_vehicle(const Eigen::Vector3d& vehicle_position_enu_m,
                                    const Eigen::Quaterniond& q_enu_body,
                                    const GimbalAngles& gimbal,
                                    const Eigen::Vector3d& camera_offset_body_m) {
  // gimbal: yaw about up, then elevation; a positive rotation about FLU y tilts x down, so -pitch
  const Eigen::Matrix3d R_base_mount =
      (Eigen::AngleAxisd(gimbal.yaw_rad, Eigen::Vector3d::UnitZ()) *
       Eigen::AngleAxisd(-gimbal.pitch_rad, Eigen::Vector3d::UnitY()))
          .toRotationMatrix();
  const Eigen::Matrix3d R_enu_body = q_enu_body.normalized().toRotationMatrix();
  Eigen::Matrix3d R_enu_base = R_enu_body;
  if (gimbal.earth_stabilised) {
    // keep only the vehicle's heading: yaw of the body x axis projected on the ground
    const Eigen::Vector3d x_enu = R_enu_body.col(0);
    const double yaw_rad = std::atan2(x_enu.y(), x_enu.x());
    R_enu_base = Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  }
  CameraPose pose;
  pose.position_enu_m = vehicle_position_enu_m + R_enu_body * camera_offset_body_m;
  pose.R_enu_cam = R_enu_base * R_base_mount * R_mount_cam();
  return pose;
}

std::optional<Eigen::Vector3d> intersect_ray_with_plane(const CameraPose& pose,
                                                        const Eigen::Vector3d& ray_cam,
                                                        double plane_height_enu_m) {
  const Eigen::Vector3d d_enu = pose.R_enu_cam * ray_cam;
  constexpr double kMinVerticalComponent = 1e-9;
  if (std::abs(d_enu.z()) < kMinVerticalComponent) return std::nullopt;
  const double t = (plane_height_enu_m - pose.position_enu_m.z()) / d_enu.z();
  if (t <= 0.0) return std::nullopt;
  return pose.position_enu_m + t * d_enu;
}

std::optional<Eigen::Vector3d> pixel_to_plane_enu(const PinholeIntrinsics& intrinsics,
                                                  const CameraPose& pose,
                                                  const Eigen::Vector2d& pixel_px,
                                                  double plane_height_enu_m) {
  return intersect_ray_with_plane(pose, intrinsics.ray_cam(pixel_px), plane_height_enu_m);
}

}  // namespace uavsim::vision
