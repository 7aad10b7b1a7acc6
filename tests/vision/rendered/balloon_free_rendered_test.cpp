// False positives on rendered frames (issue 7): the balloon detector on frames without balloons
// (the MBZIRC 2020 arena with every balloon popped, so only the poles stand; the other quad; the
// MBZIRC 2017 truck from the side and from above), and the marker detector on frames without the
// marker (the 2020 arena). Each must report nothing.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "rendered_fixture.hpp"
#include "uavsim/common/angles.hpp"
#include "uavsim/vision/balloon_detector.hpp"
#include "uavsim/vision/marker_detector.hpp"

namespace uavsim::vision::rendered {
namespace {

constexpr int kWidthPx = 640;
constexpr int kHeightPx = 480;
constexpr int kBalloons = 5;  // in mbzirc2020.xml

// mbzirc2020.xml with every balloon popped (sphere hidden, its pole standing), renderer cameras:
// uav0's forward camera plain, the same with the sky box and shadows, and the overview
RenderedWorld arena_without_balloons(uint64_t seed) {
  server::render::CameraConfig sky_and_shadows = camera("uav0_front", kWidthPx, kHeightPx);
  sky_and_shadows.flags.skybox = true;
  sky_and_shadows.flags.shadows = true;
  RenderedWorld w("mbzirc2020.xml", seed,
                  {camera("uav0_front", kWidthPx, kHeightPx), sky_and_shadows,
                   camera("overview", kWidthPx, kHeightPx)});
  for (int i = 0; i < kBalloons; ++i) {
    const int g = w.geom(balloon_part(i, "balloon"));
    server::physics::set_geom_enabled(w.world(), server::physics::geom_switch(w.world(), g), false);
  }
  return w;
}

// Frames of the balloon-free arena: around every pole at 3 to 20 m, aimed at where the balloon
// was, from below and above, uav1 in view every other frame; then the overview. Calls
// look_at_frame(frame, label) for each.
template <typename F>
void for_each_arena_frame(RenderedWorld& w, uint64_t seed, F look_at_frame) {
  const auto& balloons = w.objects.balloons->balloons();
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  int frame = 0;
  for (const auto& b : balloons) {
    for (const double d : {3.0, 8.0, 14.0, 20.0}) {
      const double az = 2.0 * common::kPi * unit(rng);
      const double height_m = frame % 2 == 0 ? 0.8 + 1.4 * unit(rng) : 3.5 + 6.0 * unit(rng);
      const Eigen::Vector3d cam = b.position_enu_m +
                                  Eigen::Vector3d(d * std::cos(az), d * std::sin(az), 0.0) +
                                  Eigen::Vector3d(0.0, 0.0, height_m - b.position_enu_m.z());
      w.place_camera("uav0_gimbal", cam, look_at(cam, b.position_enu_m));
      const Eigen::Vector3d towards = (b.position_enu_m - cam).normalized();
      const Eigen::Vector3d uav1 =
          frame % 2 == 0
              ? cam + 0.5 * d * towards + Eigen::Vector3d(-towards.y(), towards.x(), 0.0) * 0.3 * d
              : Eigen::Vector3d(10.0, -27.0, 0.0);
      server::physics::set_vehicle_state(w.world(), 1, uav1, Eigen::Quaterniond::Identity(),
                                         Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero());
      look_at_frame(w.render(frame % 4 == 1 ? 1 : 0),
                    "pole " + b.name + " frame " + std::to_string(frame));
      ++frame;
    }
  }
  look_at_frame(w.render(2), std::string("overview"));
}

TEST(BalloonRendered, NothingInBalloonFreeArenaFrames) {
  int frames = 0, false_positives = 0;
  for (const uint64_t seed : {1u, 2u}) {
    RenderedWorld w = arena_without_balloons(seed);
    BalloonDetector front({}, w.renderer->intrinsics(0));
    BalloonDetector overview({}, w.renderer->intrinsics(2));
    for_each_arena_frame(
        w, seed, [&](const server::render::CameraFrame& f, const std::string& what) {
          BalloonDetector& detector = f.camera_name == "overview" ? overview : front;
          const auto detections = detector.detect(to_bgr(f));
          ++frames;
          false_positives += static_cast<int>(detections.size());
          EXPECT_TRUE(detections.empty())
              << "seed " << seed << " " << what << ": " << detections.size()
              << " balloons, the first at ("
              << (detections.empty() ? 0.0 : detections[0].centre_px.x) << ", "
              << (detections.empty() ? 0.0 : detections[0].centre_px.y) << ")";
        });
  }
  std::printf("balloon-free arena: %d frames, %d false positives\n", frames, false_positives);
  EXPECT_EQ(frames, 2 * (kBalloons * 4 + 1));
}

TEST(BalloonRendered, NothingInFramesOfTheTruck) {
  // mbzirc2017.xml: the hexa's camera turned to look at the driving truck from the side (5 to 20 m
  // away, 1 to 8 m up) and from above, and the overview
  RenderedWorld w(
      "mbzirc2017.xml", 1,
      {camera("uav0_down", kWidthPx, kHeightPx), camera("overview", kWidthPx, kHeightPx)});
  BalloonDetector down({}, w.renderer->intrinsics(0));
  BalloonDetector overview({}, w.renderer->intrinsics(1));
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  int frames = 0;
  for (int i = 0; i < 24; ++i) {
    w.sim->run_until(2.5 * i);
    w.objects.trucks.at(0)->before_step(*w.sim);
    const server::objects::TruckState truck = w.objects.trucks.at(0)->state(w.sim->time_s());
    const double az = 2.0 * common::kPi * unit(rng);
    const double d = i % 3 == 2 ? 0.5 : 5.0 + 15.0 * unit(rng);
    const double height_m = i % 3 == 2 ? 10.0 : 1.0 + 7.0 * unit(rng);
    const Eigen::Vector3d cam =
        truck.position_enu_m + Eigen::Vector3d(d * std::cos(az), d * std::sin(az), height_m);
    w.place_camera("uav0_gimbal", cam,
                   look_at(cam, truck.position_enu_m + Eigen::Vector3d(0, 0, 1)));
    const auto detections = down.detect(to_bgr(w.render(0)));
    ++frames;
    EXPECT_TRUE(detections.empty()) << "frame " << i << " at t = " << w.sim->time_s();
  }
  EXPECT_TRUE(overview.detect(to_bgr(w.render(1))).empty()) << "overview";
  std::printf("truck frames: %d without a balloon\n", frames + 1);
}

TEST(MarkerRendered, NothingInMarkerFreeFrames) {
  // the 2020 arena (poles, balloons popped or not, white arena lines, the quads) through the
  // forward camera and the overview
  RenderedWorld w = arena_without_balloons(3);
  MarkerDetector detector;
  int frames = 0;
  for_each_arena_frame(w, 3, [&](const server::render::CameraFrame& f, const std::string& what) {
    ++frames;
    const auto d = detector.detect(to_bgr(f));
    EXPECT_FALSE(d.has_value()) << what << ": a marker at (" << (d ? d->centre_px.x : 0.0) << ", "
                                << (d ? d->centre_px.y : 0.0) << ")";
  });
  EXPECT_EQ(frames, kBalloons * 4 + 1);
}

}  // namespace
}  // namespace uavsim::vision::rendered
