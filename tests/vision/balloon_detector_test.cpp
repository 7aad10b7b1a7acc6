// Balloon detector and tracker on synthetic frames: a Lambert-shaded green sphere of known diameter
// at a known 3D position, over sky and sand, with pixel noise (synthetic_scene.hpp).
#include "uavsim/vision/balloon_detector.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

#include "uavsim/common/angles.hpp"
#include "uavsim/vision/synthetic_scene.hpp"

namespace uavsim::vision {
namespace {

constexpr double kBalloonDiameterM = 0.6;
constexpr double kMinDetectionRate = 0.95;  // in frames where the balloon is >= 20 px wide
constexpr double kMaxRangeError = 0.10;     // relative, 3 to 25 m
constexpr double kNoiseSigma = 3.0;
constexpr double kRangeTolM = 1e-6;
constexpr double kPosTolM = 1e-9;

// 640 x 480, 60 deg horizontal field of view: fx = 320 / tan(30 deg) = 554.3 px
PinholeIntrinsics test_camera() {
  return PinholeIntrinsics::from_fovy(640, 480,
                                      2.0 * std::atan(240.0 / (320.0 / std::tan(common::kPi / 6))));
}

struct Scene {
  cv::Mat image;
  Eigen::Vector3d centre_cam_m;
  double width_px;  // apparent diameter
};

// a balloon at a random range in [min, max] m and a random direction that keeps it in the frame
Scene random_balloon_scene(std::mt19937_64& rng, const PinholeIntrinsics& k, double min_range_m,
                           double max_range_m) {
  std::uniform_real_distribution<double> range(min_range_m, max_range_m);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  Scene s;
  const double d = range(rng);
  const double r_px = k.fx_px * 0.5 * kBalloonDiameterM / d;
  const double margin = 1.3 * r_px + 4.0;
  const Eigen::Vector2d px(margin + unit(rng) * (k.width_px - 1 - 2 * margin),
                           margin + unit(rng) * (k.height_px - 1 - 2 * margin));
  s.centre_cam_m = k.ray_cam(px) * d;
  s.width_px = 2.0 * r_px;
  s.image = synthetic::sky_sand_background(k, 150 + 180 * unit(rng), rng());
  // balloon greens vary a little; the sun is above and slightly behind the camera
  const cv::Scalar albedo(35 + 20 * unit(rng), 150 + 50 * unit(rng), 40 + 20 * unit(rng));
  const Eigen::Vector3d light = Eigen::Vector3d(0.3 * (unit(rng) - 0.5), -1.0, -0.3).normalized();
  synthetic::render_sphere(k, s.centre_cam_m, kBalloonDiameterM, albedo, light, &s.image);
  synthetic::add_noise(kNoiseSigma, rng(), &s.image);
  return s;
}

TEST(BalloonDetector, RangeFromKnownDiameterOnAxisAndOffAxis) {
  // on axis: a sphere of radius R at range d subtends sin(a) = R / d, its image radius is f tan(a)
  const auto k = test_camera();
  const double d = 10.0, rr = 0.3;
  const double a = std::asin(rr / d);
  const Eigen::Vector3d p =
      sphere_position_from_circle(k, {k.cx_px, k.cy_px}, k.fx_px * std::tan(a), 2 * rr);
  EXPECT_NEAR(p.norm(), d, kRangeTolM);
  EXPECT_NEAR(p.x(), 0.0, kPosTolM);
}

TEST(BalloonDetector, DetectsShadedBalloonsAndMeasuresRange) {
  const auto k = test_camera();
  BalloonDetectorParams params;
  params.balloon_diameter_m = kBalloonDiameterM;
  BalloonDetector detector(params, k);
  std::mt19937_64 rng(2020);

  constexpr int kFrames = 200;
  int big = 0, big_hits = 0, small = 0, small_hits = 0, extra = 0;
  double worst_range_error = 0.0, sum_range_error = 0.0, worst_centre_px = 0.0;
  int ranged = 0;
  for (int i = 0; i < kFrames; ++i) {
    const Scene s = random_balloon_scene(rng, k, 3.0, 25.0);
    const auto detections = detector.detect(s.image);
    const Eigen::Vector2d truth_px = k.project(s.centre_cam_m);
    const BalloonDetection* hit = nullptr;
    for (const auto& d : detections) {
      if (std::hypot(d.centre_px.x - truth_px.x(), d.centre_px.y - truth_px.y()) <
          0.5 * s.width_px) {
        hit = &d;
      } else {
        ++extra;
      }
    }
    (s.width_px >= 20.0 ? big : small) += 1;
    if (!hit) continue;
    (s.width_px >= 20.0 ? big_hits : small_hits) += 1;
    const double err = std::abs(hit->range_m - s.centre_cam_m.norm()) / s.centre_cam_m.norm();
    worst_range_error = std::max(worst_range_error, err);
    sum_range_error += err;
    ++ranged;
    worst_centre_px = std::max(worst_centre_px, std::hypot(hit->centre_px.x - truth_px.x(),
                                                           hit->centre_px.y - truth_px.y()));
    EXPECT_LT(err, kMaxRangeError) << "frame " << i << " range " << s.centre_cam_m.norm() << " m";
  }
  const double big_rate = static_cast<double>(big_hits) / big;
  std::printf(
      "[ balloons ] >=20 px: %d/%d detected (%.1f%%); <20 px: %d/%d; range error mean %.2f%% "
      "max %.2f%%; centre error max %.2f px; false detections %d\n",
      big_hits, big, 100 * big_rate, small_hits, small, 100 * sum_range_error / ranged,
      100 * worst_range_error, worst_centre_px, extra);
  RecordProperty("detection_rate_ge_20px", std::to_string(big_rate));
  RecordProperty("max_range_error", std::to_string(worst_range_error));
  EXPECT_GE(big_rate, kMinDetectionRate);
  EXPECT_EQ(extra, 0);
}

TEST(BalloonDetector, NothingInBalloonFreeFramesWithGreenClutter) {
  const auto k = test_camera();
  BalloonDetector detector({}, k);
  std::mt19937_64 rng(7);
  int detections = 0;
  for (int i = 0; i < 40; ++i) {
    cv::Mat image = synthetic::sky_sand_background(k, 120 + 240 * (i % 5) / 4.0, rng());
    // half the frames carry a bush, a green board and a green pole
    if (i % 2 == 1) synthetic::render_green_clutter(rng(), &image);
    synthetic::add_noise(kNoiseSigma, rng(), &image);
    detections += static_cast<int>(detector.detect(image).size());
  }
  EXPECT_EQ(detections, 0);
}

TEST(BalloonDetector, BalloonNextToClutterIsStillFound) {
  const auto k = test_camera();
  BalloonDetector detector({}, k);
  std::mt19937_64 rng(11);
  cv::Mat image = synthetic::sky_sand_background(k, 240, rng());
  synthetic::render_green_clutter(3, &image);
  const Eigen::Vector3d centre = k.ray_cam({520, 120}) * 8.0;
  synthetic::render_sphere(k, centre, kBalloonDiameterM, {45, 170, 50}, {0, -1, 0}, &image);
  synthetic::add_noise(kNoiseSigma, rng(), &image);
  const auto detections = detector.detect(image);
  ASSERT_EQ(detections.size(), 1u);
  EXPECT_NEAR(detections[0].range_m, 8.0, kMaxRangeError * 8.0);
}

TEST(BalloonTracker, ConfirmsAfterConsecutiveHitsAndIgnoresFlicker) {
  BalloonTrackerParams params;
  params.confirm_hits = 3;
  BalloonTracker tracker(params);
  const Eigen::Vector3d balloon(10, 2, 3);
  // a one-frame false positive, then the balloon in three consecutive frames
  EXPECT_TRUE(tracker.update(0, {Eigen::Vector3d(-5, 0, 1)}).empty());
  EXPECT_TRUE(tracker.update(100'000, {balloon}).empty());
  EXPECT_TRUE(tracker.update(200'000, {balloon}).empty());
  const auto confirmed = tracker.update(300'000, {balloon});
  ASSERT_EQ(confirmed.size(), 1u);
  EXPECT_NEAR((confirmed[0].position_m - balloon).norm(), 0.0, kPosTolM);
  // the false positive was never confirmed and has been dropped after max_misses
  for (int i = 4; i < 8; ++i) tracker.update(i * 100'000, {balloon});
  EXPECT_EQ(tracker.tracks().size(), 1u);
}

TEST(BalloonTracker, LowPassReducesNoise) {
  BalloonTrackerParams params;
  params.confirm_hits = 1;
  params.lowpass_tau_s = 0.5;
  BalloonTracker tracker(params);
  std::mt19937_64 rng(5);
  std::normal_distribution<double> noise(0.0, 0.3);
  const Eigen::Vector3d balloon(12, -1, 3);
  double raw_sq = 0, filtered_sq = 0;
  int n = 0;
  for (int i = 0; i < 300; ++i) {
    const Eigen::Vector3d z = balloon + Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
    const auto out = tracker.update(i * 100'000, {z});  // 10 Hz
    ASSERT_EQ(out.size(), 1u);
    if (i < 20) continue;  // settle
    raw_sq += (z - balloon).squaredNorm();
    filtered_sq += (out[0].position_m - balloon).squaredNorm();
    ++n;
  }
  // first-order low-pass at dt = 0.1, tau = 0.5: alpha = 0.181, variance ratio alpha / (2 - alpha)
  // = 0.0997, so the rms shrinks about 3.2x
  EXPECT_LT(std::sqrt(filtered_sq / n), 0.45 * std::sqrt(raw_sq / n));
}

}  // namespace
}  // namespace uavsim::vision
