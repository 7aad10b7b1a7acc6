// Landing-marker detector on synthetic frames: the marker texture projected by the homography of a
// known camera pose (synthetic_scene.hpp), seen from a down-looking camera on a tilted UAV.
#include "uavsim/vision/marker_detector.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <opencv2/imgproc.hpp>
#include <random>

#include "uavsim/common/angles.hpp"
#include "uavsim/vision/synthetic_scene.hpp"

namespace uavsim::vision {
namespace {

constexpr double kMaxPositionErrorM = 0.3;
constexpr double kDeckHeightM = 1.2;  // truck deck above the ground
constexpr double kAltitudeM = 10.0;   // UAV above the ground
constexpr double kNoiseSigma = 4.0;
constexpr double kRadiusTolPx = 1.0;
constexpr double kCentreTolPx = 0.5;

PinholeIntrinsics down_camera() { return PinholeIntrinsics::from_fovy(640, 480, common::kPi / 3); }

struct Trial {
  double worst_error_m = 0.0;
  double sum_error_m = 0.0;
  int detected = 0;
  int frames = 0;
};

// UAV at 10 m, tilted by up to max_tilt_rad in roll and pitch, random heading; the marker somewhere
// in the view; the pose passed to the detector is the one that rendered the frame
Trial run_trials(bool earth_stabilised, double max_tilt_rad, int frames, uint64_t seed) {
  const auto k = down_camera();
  MarkerDetector detector;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  Trial t;
  for (int i = 0; i < frames; ++i) {
    const Eigen::Vector3d uav(20 * unit(rng), 15 * unit(rng), kAltitudeM);
    const auto q = q_enu_body_from_rpy(max_tilt_rad * unit(rng), max_tilt_rad * unit(rng),
                                       common::kPi * unit(rng));
    const CameraPose pose = camera_pose_from_vehicle(
        uav, q, {-common::kPi / 2, 0.0, earth_stabilised}, {0.05, 0.0, -0.1});
    // a marker centre that lands in the inner 60% of the image
    const Eigen::Vector2d px(k.cx_px + 0.3 * k.width_px * unit(rng),
                             k.cy_px + 0.3 * k.height_px * unit(rng));
    const Eigen::Vector3d marker = *pixel_to_plane_enu(k, pose, px, kDeckHeightM);
    cv::Mat image = synthetic::sand_background(k, rng());
    synthetic::render_marker(k, pose, LandingMarkerGeometry{}, marker.head<2>(),
                             common::kPi * unit(rng), kDeckHeightM, &image);
    synthetic::add_noise(kNoiseSigma, rng(), &image);
    ++t.frames;
    const auto d = detector.detect(image);
    if (!d) continue;
    const auto p = marker_position_enu(*d, k, pose, kDeckHeightM);
    if (!p) continue;
    ++t.detected;
    const double err = (p->head<2>() - marker.head<2>()).norm();
    t.worst_error_m = std::max(t.worst_error_m, err);
    t.sum_error_m += err;
  }
  return t;
}

TEST(MarkerDetector, LocatesMarkerFromTenMetresWithBodyFixedTiltedCamera) {
  // body-fixed gimbal: the UAV's 10 deg roll/pitch tilts the view; the pose accounts for it
  const Trial t = run_trials(false, 10.0 * common::kPi / 180, 40, 2017);
  std::printf(
      "[ marker   ] body-fixed, tilt <= 10 deg: %d/%d detected, error mean %.3f m max %.3f m\n",
      t.detected, t.frames, t.sum_error_m / std::max(t.detected, 1), t.worst_error_m);
  EXPECT_EQ(t.detected, t.frames);
  EXPECT_LT(t.worst_error_m, kMaxPositionErrorM);
}

TEST(MarkerDetector, LocatesMarkerWithStabilisedGimbal) {
  const Trial t = run_trials(true, 15.0 * common::kPi / 180, 20, 71);
  std::printf("[ marker   ] stabilised: %d/%d detected, error mean %.3f m max %.3f m\n", t.detected,
              t.frames, t.sum_error_m / std::max(t.detected, 1), t.worst_error_m);
  EXPECT_EQ(t.detected, t.frames);
  EXPECT_LT(t.worst_error_m, kMaxPositionErrorM);
}

TEST(MarkerDetector, RadiusMatchesPinholeScale) {
  // straight down from 10 m to a deck at 1.2 m: r = f * 0.65 / 8.8 = 415.7 * 0.0739 = 30.7 px
  const auto k = down_camera();
  const CameraPose pose = camera_pose_from_vehicle(
      {0, 0, kAltitudeM}, Eigen::Quaterniond::Identity(), {-common::kPi / 2, 0.0, true});
  cv::Mat image = synthetic::sand_background(k, 1);
  synthetic::render_marker(k, pose, LandingMarkerGeometry{}, {0, 0}, 0.3, kDeckHeightM, &image);
  MarkerDetector detector;
  const auto d = detector.detect(image);
  ASSERT_TRUE(d.has_value());
  EXPECT_NEAR(d->radius_px, k.fx_px * 0.65 / (kAltitudeM - kDeckHeightM), kRadiusTolPx);
  EXPECT_NEAR(d->centre_px.x, k.cx_px, kCentreTolPx);
  EXPECT_NEAR(d->centre_px.y, k.cy_px, kCentreTolPx);
}

TEST(MarkerDetector, NoMarkerNoDetection) {
  const auto k = down_camera();
  MarkerDetector detector;
  for (uint64_t seed = 0; seed < 10; ++seed) {
    cv::Mat image = synthetic::sand_background(k, seed);
    // a dark square without the ring, and a white disc without a hole: neither is the marker
    cv::rectangle(image, cv::Rect(100, 100, 80, 80), {45, 45, 45}, cv::FILLED);
    cv::circle(image, {400, 300}, 30, {235, 235, 235}, cv::FILLED, cv::LINE_AA);
    synthetic::add_noise(kNoiseSigma, seed + 100, &image);
    EXPECT_FALSE(detector.detect(image).has_value()) << "seed " << seed;
  }
}

}  // namespace
}  // namespace uavsim::vision
