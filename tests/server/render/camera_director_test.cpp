// The recording camera's director (--record-camera follow|top): vehicles in frame, smoothed in sim
// time, never closer than the minimum distance.
#include "render/camera_director.hpp"

#include <gtest/gtest.h>

#include <Eigen/LU>
#include <cmath>
#include <vector>

#include "render/frame_service.hpp"
#include "render/overlay.hpp"
#include "uavsim/common/angles.hpp"

namespace uavsim::server::render {
namespace {

constexpr double kTol = 1e-9;
constexpr double kPosTol_m = 1e-6;      // positions the director works out, up to round-off
constexpr double kArrivedTol_m = 1e-3;  // after 13 time constants of smoothing
constexpr int kRingColourTol = 40;      // colour levels out of 255

// a 640 x 480 pinhole camera with the director's default 45 deg vertical field of view
FrameCamera camera_640x480() {
  FrameCamera c;
  c.width_px = 640;
  c.height_px = 480;
  c.fy_px = 240.0 / std::tan(22.5 * common::kPi / 180.0);  // 579.4 px
  c.fx_px = c.fy_px;
  c.cx_px = 320.0;
  c.cy_px = 240.0;
  return c;
}

bool inside(const FrameCamera& c, const CameraPose& pose, const Eigen::Vector3d& p) {
  const auto px = project_to_pixel(c, pose.position_enu_m, pose.R_enu_cam, p);
  return px && px->x() >= 0 && px->x() < c.width_px && px->y() >= 0 && px->y() < c.height_px;
}

TEST(CameraDirector, LookAtRotationIsARightHandedOpenCvFrame) {
  const Eigen::Matrix3d R = look_at_rotation(Eigen::Vector3d(0, -10, 5), Eigen::Vector3d(0, 0, 0));
  EXPECT_NEAR(R.determinant(), 1.0, kTol);
  EXPECT_NEAR((R.transpose() * R - Eigen::Matrix3d::Identity()).norm(), 0.0, kTol);
  // looking north and down: x right = east, y down has a negative z component
  EXPECT_NEAR(R.col(0).x(), 1.0, kTol);
  EXPECT_LT(R.col(1).z(), 0.0);
  // straight down: north is image up (y down = south)
  const Eigen::Matrix3d D = look_at_rotation(Eigen::Vector3d(0, 0, 10), Eigen::Vector3d(0, 0, 0));
  EXPECT_NEAR(D.col(2).z(), -1.0, kTol);
  EXPECT_NEAR(D.col(1).y(), -1.0, kTol);
}

TEST(CameraDirector, KeepsSpreadVehiclesInFrame) {
  const FrameCamera c = camera_640x480();
  CameraDirector director(DirectorParams{});
  const std::vector<Eigen::Vector3d> v{{-30, 10, 2}, {40, -20, 25}, {5, 60, 10}};
  const CameraPose pose = director.aim(0.0, v);
  for (const Eigen::Vector3d& p : v) EXPECT_TRUE(inside(c, pose, p)) << p.transpose();
}

TEST(CameraDirector, NeverCloserThanTheMinimumDistance) {
  DirectorParams p;
  p.min_distance_m = 8.0;
  CameraDirector director(p);
  const Eigen::Vector3d quad(3, 4, 1);
  const CameraPose pose = director.aim(0.0, {quad});
  EXPECT_NEAR((pose.position_enu_m - quad).norm(), 8.0, kPosTol_m);
  // a 0.55 m quad at 8 m: 579.4 * 0.55 / 8 = 39.8 px across
  const FrameCamera c = camera_640x480();
  EXPECT_TRUE(inside(c, pose, quad));
}

TEST(CameraDirector, FollowsANamedVehicleOnly) {
  DirectorParams p;
  p.vehicle = 1;
  CameraDirector director(p);
  const CameraPose pose = director.aim(0.0, {{-500, 0, 1}, {10, 20, 5}});
  EXPECT_NEAR((pose.position_enu_m - Eigen::Vector3d(10, 20, 5)).norm(), p.min_distance_m,
              kPosTol_m);
}

TEST(CameraDirector, SmoothsAJumpOverSimTime) {
  DirectorParams p;
  p.look_at_tau_s = 1.0;
  CameraDirector director(p);
  const CameraPose a = director.aim(0.0, {{0, 0, 5}});
  // the vehicle jumps 10 m east: one 1/15 s frame later the camera has moved 1 - exp(-1/15) = 6.4 %
  // of it
  const CameraPose b = director.aim(1.0 / 15.0, {{10, 0, 5}});
  EXPECT_NEAR(b.position_enu_m.x() - a.position_enu_m.x(), 10.0 * (1.0 - std::exp(-1.0 / 15.0)),
              kPosTol_m);
  // after many time constants it has arrived
  CameraPose c = b;
  for (int k = 2; k < 200; ++k) c = director.aim(k / 15.0, {{10, 0, 5}});
  EXPECT_NEAR(c.position_enu_m.x(), 10.0, kArrivedTol_m);
  // a reset (earlier sim time) jumps
  const CameraPose d = director.aim(0.0, {{-20, 0, 5}});
  EXPECT_NEAR(d.position_enu_m.x(), -20.0, kTol);
}

TEST(CameraDirector, TopLooksStraightDownOverTheVehicles) {
  DirectorParams p;
  p.mode = DirectorMode::kTop;
  CameraDirector director(p);
  const std::vector<Eigen::Vector3d> v{{-20, 0, 10}, {20, 10, 10}};
  const CameraPose pose = director.aim(0.0, v);
  EXPECT_NEAR(pose.R_enu_cam.col(2).z(), -1.0, kTol);
  EXPECT_NEAR(pose.position_enu_m.x(), 0.0, kTol);
  EXPECT_NEAR(pose.position_enu_m.y(), 5.0, kTol);
  const FrameCamera c = camera_640x480();
  for (const Eigen::Vector3d& x : v) EXPECT_TRUE(inside(c, pose, x));
}

TEST(Overlay, DrawsTimeLabelsAndEvents) {
  const FrameCamera c = camera_640x480();
  std::vector<uint8_t> img(640 * 480 * 3, 90), plain = img;
  OverlayInfo info;
  info.time_s = 12.3;
  info.vehicles = {{"uav0", "GUIDED"}};
  info.events = {{"12.0 s uav0 balloon_popped b1", 0}};
  info.counters = {"balloons popped 1/5"};
  // where the balloon was popped: 2 m east of the vehicle, 10 m in front of the camera: u = 319.5 +
  // 579.4 * 2 / 10 = 435
  info.markers = {{Eigen::Vector3d(2, 0, 0), 0, "uav0 pop 1"}};
  const CameraPose pose{Eigen::Vector3d(0, -10, 0),
                        look_at_rotation(Eigen::Vector3d(0, -10, 0), Eigen::Vector3d(0, 0, 0))};
  draw_overlay(info, c, pose.position_enu_m, pose.R_enu_cam, {Eigen::Vector3d(0, 0, 0)},
               img.data());
  // count changed pixels in a region (x0, y0, w, h)
  auto changed = [&](int x0, int y0, int w, int h) {
    int n = 0;
    for (int y = y0; y < y0 + h; ++y) {
      for (int x = x0; x < x0 + w; ++x) {
        const size_t i = (static_cast<size_t>(y) * 640 + x) * 3;
        n += img[i] != plain[i] || img[i + 1] != plain[i + 1] || img[i + 2] != plain[i + 2];
      }
    }
    return n;
  };
  const PixelRect t = overlay_time_rect();
  EXPECT_GT(changed(t.x_px, t.y_px, t.width_px, t.height_px), 50);  // "t = 12.3 s"
  EXPECT_GT(changed(320, 210, 200, 40), 50);                        // the label right of the centre
  EXPECT_GT(changed(0, 440, 300, 40), 50);                          // the event line at the bottom
  EXPECT_EQ(changed(0, 240, 200, 150), 0);                          // elsewhere untouched
  // the ring around the vehicle (at the centre), kVehicleRingPx out, in uav0's colour
  uint8_t yellow[3];
  vehicle_colour_rgb(0, yellow);
  const size_t ring = (static_cast<size_t>(240) * 640 + 320 - kVehicleRingPx) * 3;
  EXPECT_NEAR(img[ring], yellow[0], kRingColourTol);
  EXPECT_NEAR(img[ring + 1], yellow[1], kRingColourTol);
  EXPECT_NEAR(img[ring + 2], yellow[2], kRingColourTol);
  EXPECT_EQ(changed(316, 236, 8, 8), 0);  // the vehicle itself is not painted over
  // the marker's cross at (435, 240)
  EXPECT_GT(changed(429, 234, 13, 13), 30);
}

}  // namespace
}  // namespace uavsim::server::render
