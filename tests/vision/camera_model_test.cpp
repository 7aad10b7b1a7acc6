#include "uavsim/vision/camera_model.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "uavsim/common/angles.hpp"

namespace uavsim::vision {
namespace {

constexpr double kTolM = 1e-9;
constexpr double kTolPx = 1e-9;
constexpr double kExactTol = 1e-12;
constexpr double kEdgeAngleTolRad = 1e-2;

TEST(PinholeIntrinsics, FocalLengthFromVerticalFov) {
  // fovy 90 deg on 480 rows: fy = 240 / tan(45 deg) = 240 px; square pixels
  const auto k = PinholeIntrinsics::from_fovy(640, 480, common::kPi / 2);
  EXPECT_NEAR(k.fy_px, 240.0, kTolPx);
  EXPECT_NEAR(k.fx_px, 240.0, kTolPx);
  EXPECT_NEAR(k.cx_px, 319.5, kTolPx);
  EXPECT_NEAR(k.cy_px, 239.5, kTolPx);
  // the top edge of the image (row -0.5) is 45 deg above the axis
  const Eigen::Vector3d top = k.ray_cam({319.5, -0.5});
  EXPECT_NEAR(std::atan2(-top.y(), top.z()), common::kPi / 4, kEdgeAngleTolRad);
}

TEST(PinholeIntrinsics, ProjectInvertsRay) {
  const auto k = PinholeIntrinsics::from_fovy(320, 240, 0.8);
  const Eigen::Vector2d px(12.25, 201.5);
  const Eigen::Vector3d ray = k.ray_cam(px);
  EXPECT_NEAR(ray.norm(), 1.0, kExactTol);
  EXPECT_NEAR((k.project(7.0 * ray) - px).norm(), 0.0, kTolPx);
}

TEST(CameraPose, DownLookingGimbalAxes) {
  // vehicle level, facing east (yaw 0); gimbal straight down: optical axis = -z_enu, image top =
  // east, image right = south
  const auto pose = camera_pose_from_vehicle({1, 2, 10}, Eigen::Quaterniond::Identity(),
                                             GimbalAngles{-common::kPi / 2, 0.0, true});
  EXPECT_NEAR((pose.R_enu_cam * Eigen::Vector3d::UnitZ() - Eigen::Vector3d(0, 0, -1)).norm(), 0,
              kTolM);
  EXPECT_NEAR((pose.R_enu_cam * -Eigen::Vector3d::UnitY() - Eigen::Vector3d(1, 0, 0)).norm(), 0,
              kTolM);
  EXPECT_NEAR((pose.R_enu_cam * Eigen::Vector3d::UnitX() - Eigen::Vector3d(0, -1, 0)).norm(), 0,
              kTolM);
}

TEST(CameraPose, ForwardCameraFollowsYaw) {
  // facing north (yaw 90 deg), gimbal level: optical axis north, image right = east
  const auto pose = camera_pose_from_vehicle({0, 0, 3}, q_enu_body_from_rpy(0, 0, common::kPi / 2),
                                             GimbalAngles{0.0, 0.0, false});
  EXPECT_NEAR((pose.R_enu_cam * Eigen::Vector3d::UnitZ() - Eigen::Vector3d(0, 1, 0)).norm(), 0,
              kTolM);
  EXPECT_NEAR((pose.R_enu_cam * Eigen::Vector3d::UnitX() - Eigen::Vector3d(1, 0, 0)).norm(), 0,
              kTolM);
}

TEST(CameraPose, StabilisedGimbalIgnoresRollAndPitch) {
  const auto q = q_enu_body_from_rpy(0.2, -0.15, 0.7);
  const auto stabilised =
      camera_pose_from_vehicle({0, 0, 5}, q, GimbalAngles{-common::kPi / 2, 0, true});
  const auto level = camera_pose_from_vehicle({0, 0, 5}, q_enu_body_from_rpy(0, 0, 0.7),
                                              GimbalAngles{-common::kPi / 2, 0, true});
  EXPECT_NEAR((stabilised.R_enu_cam - level.R_enu_cam).norm(), 0.0, kExactTol);
  const auto body_fixed =
      camera_pose_from_vehicle({0, 0, 5}, q, GimbalAngles{-common::kPi / 2, 0, false});
  EXPECT_GT((body_fixed.R_enu_cam - level.R_enu_cam).norm(), 0.1);
}

TEST(CameraPose, PixelToGroundHitsWhatProjects) {
  // a tilted body-fixed camera: project a ground point, back-project the pixel onto the plane
  const auto pose = camera_pose_from_vehicle({4, -3, 12}, q_enu_body_from_rpy(0.1, 0.08, 1.1),
                                             GimbalAngles{-1.2, 0.1, false}, {0.1, 0, -0.05});
  const auto k = PinholeIntrinsics::from_fovy(640, 480, 1.0);
  const Eigen::Vector3d ground(6.0, -1.0, 1.5);
  const Eigen::Vector2d px = k.project(pose.enu_to_cam(ground));
  ASSERT_TRUE(k.contains(px));
  const auto back = pixel_to_plane_enu(k, pose, px, 1.5);
  ASSERT_TRUE(back.has_value());
  EXPECT_NEAR((*back - ground).norm(), 0.0, kTolM);
}

TEST(CameraPose, RayAwayFromPlaneHasNoIntersection) {
  const auto pose = camera_pose_from_vehicle({0, 0, 10}, Eigen::Quaterniond::Identity(),
                                             GimbalAngles{0.3, 0, true});  // looking up
  EXPECT_FALSE(intersect_ray_with_plane(pose, Eigen::Vector3d::UnitZ(), 0.0).has_value());
}

}  // namespace
}  // namespace uavsim::vision
