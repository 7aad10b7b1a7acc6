// Vision benchmarks: detector cost per frame at the camera sizes missions use (seed 7.1 ran its
// marker detector at ~7 fps on a TX1; these numbers say how much of a companion computer ours
// needs). Frames are synthetic (synthetic_scene.hpp): a shaded balloon with green clutter over sky
// and sand, or the landing marker seen from 10 m. Report ms/frame from the time column; items/s is
// frames/s.
#include <benchmark/benchmark.h>

#include <cmath>

#include "uavsim/vision/balloon_detector.hpp"
#include "uavsim/vision/eight_track.hpp"
#include "uavsim/vision/marker_detector.hpp"
#include "uavsim/vision/synthetic_scene.hpp"
#include "uavsim/vision/track_kalman.hpp"

namespace {

using namespace uavsim::vision;

// 60 deg horizontal field of view at any size
PinholeIntrinsics camera(int width, int height) {
  const double f = 0.5 * width / std::tan(M_PI / 6);
  return PinholeIntrinsics::from_fovy(width, height, 2.0 * std::atan(0.5 * height / f));
}

void BM_BalloonDetect(benchmark::State& state, int width, int height) {
  const auto k = camera(width, height);
  cv::Mat image = synthetic::sky_sand_background(k, 0.45 * height, 1);
  synthetic::render_green_clutter(2, &image);
  synthetic::render_sphere(k, k.ray_cam({0.7 * width, 0.3 * height}) * 8.0, 0.6, {45, 170, 50},
                           {0, -1, 0}, &image);
  synthetic::add_noise(3.0, 3, &image);
  BalloonDetector detector({}, k);
  for (auto _ : state) benchmark::DoNotOptimize(detector.detect(image));
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK_CAPTURE(BM_BalloonDetect, 320x240, 320, 240)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_BalloonDetect, 640x480, 640, 480)->Unit(benchmark::kMillisecond);

void BM_MarkerDetect(benchmark::State& state, int width, int height) {
  const auto k = camera(width, height);
  const CameraPose pose = camera_pose_from_vehicle({0, 0, 10}, q_enu_body_from_rpy(0.1, -0.05, 0.4),
                                                   {-M_PI / 2, 0.0, false});
  cv::Mat image = synthetic::sand_background(k, 1);
  synthetic::render_marker(k, pose, LandingMarkerGeometry{}, {1.0, -0.5}, 0.3, 1.2, &image);
  synthetic::add_noise(4.0, 3, &image);
  MarkerDetector detector;
  for (auto _ : state) benchmark::DoNotOptimize(detector.detect(image));
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK_CAPTURE(BM_MarkerDetect, 320x240, 320, 240)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_MarkerDetect, 640x480, 640, 480)->Unit(benchmark::kMillisecond);

// one Kalman correction (projection onto the eight + update) and one extrapolation to "now"
void BM_TrackKalmanUpdate(benchmark::State& state) {
  const EightTrack track;
  TrackKalman filter(track);
  int64_t t_us = 0;
  double s = 0.0;
  for (auto _ : state) {
    filter.add_measurement(t_us, track.point_enu(s));
    benchmark::DoNotOptimize(filter.estimate_at(t_us + 150'000));
    t_us += 142'857;
    s += 0.6;
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_TrackKalmanUpdate);

}  // namespace

BENCHMARK_MAIN();
