// Vision benchmarks: detector cost per frame at the camera sizes missions use (seed 7.1 ran its
// marker detector at ~7 fps on a TX1; these numbers say how much of a companion computer ours
// needs). Frames are synthetic (synthetic_scene.hpp): a shaded balloon with green clutter over sky
// and sand, or the landing marker seen from 10 m; the BM_*Rendered cases run the same detectors on
// frames that the simulator's renderer draws of the shipped MBZIRC worlds (rendered once, before
// timing). Report ms/frame from the time column; items/s is frames/s.
#include <benchmark/benchmark.h>
#include <mujoco/mujoco.h>

#include <cmath>
#include <memory>
#include <opencv2/imgproc.hpp>
#include <string>

#include "objects/world_objects.hpp"
#include "physics/object_bodies.hpp"
#include "physics/world.hpp"
#include "render/camera_renderer.hpp"
#include "sim/simulation.hpp"
#include "uavsim/common/angles.hpp"
#include "uavsim/vision/balloon_detector.hpp"
#include "uavsim/vision/eight_track.hpp"
#include "uavsim/vision/marker_detector.hpp"
#include "uavsim/vision/synthetic_scene.hpp"
#include "uavsim/vision/track_kalman.hpp"

namespace {

using namespace uavsim::vision;
using uavsim::common::kPi;

// 60 deg horizontal field of view at any size
PinholeIntrinsics camera(int width, int height) {
  const double f = 0.5 * width / std::tan(kPi / 6);
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
                                                   {-kPi / 2, 0.0, false});
  cv::Mat image = synthetic::sand_background(k, 1);
  synthetic::render_marker(k, pose, LandingMarkerGeometry{}, {1.0, -0.5}, 0.3, 1.2, &image);
  synthetic::add_noise(4.0, 3, &image);
  MarkerDetector detector;
  for (auto _ : state) benchmark::DoNotOptimize(detector.detect(image));
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK_CAPTURE(BM_MarkerDetect, 320x240, 320, 240)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_MarkerDetect, 640x480, 640, 480)->Unit(benchmark::kMillisecond);

// A frame of a shipped world (models/worlds/NAME) from one of its cameras, rendered after
// place(sim) has put the camera and objects where the case wants them.
struct RenderedFrame {
  cv::Mat bgr;
  PinholeIntrinsics intrinsics;
};

template <typename Place>
RenderedFrame render_world(const std::string& world, const std::string& camera, int width,
                           int height, Place place) {
  namespace server = uavsim::server;
  server::physics::ComposeOptions o;
  o.models_dir = UAVSIM_MODELS_DIR;
  server::sim::Simulation sim(
      server::physics::World::load(std::string(UAVSIM_MODELS_DIR) + "/worlds/" + world, o), {});
  const server::objects::ObjectSet objects = server::objects::add_world_objects(sim);
  server::render::CameraConfig config;
  config.camera = camera;
  config.width_px = width;
  config.height_px = height;
  server::render::CameraRenderer renderer(sim.world().model(), {config});
  place(sim, objects);
  mj_forward(sim.world().model(), sim.world().data());
  server::render::CameraFrame f;
  renderer.render(sim.world().data(), 0, &f);
  RenderedFrame out;
  cv::cvtColor(cv::Mat(f.height_px, f.width_px, CV_8UC3, f.pixels.data()), out.bgr,
               cv::COLOR_RGB2BGR);
  const auto& k = f.intrinsics;
  out.intrinsics = {k.fx_px, k.fy_px, k.cx_px, k.cy_px, k.width_px, k.height_px};
  return out;
}

// a gimbal body's orientation looking along yaw, pitch (up positive); its camera looks along +x
Eigen::Quaterniond look(double yaw_rad, double pitch_rad) {
  return Eigen::Quaterniond(Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitZ()) *
                            Eigen::AngleAxisd(-pitch_rad, Eigen::Vector3d::UnitY()));
}

// mbzirc2020.xml, uav0's forward camera (fovy 22 deg) 10 m from a balloon, slightly below it, with
// other balloons and poles behind and uav1 beside it
void BM_BalloonDetectRendered(benchmark::State& state, int width, int height) {
  namespace server = uavsim::server;
  const RenderedFrame frame = render_world(
      "mbzirc2020.xml", "uav0_front", width, height,
      [](server::sim::Simulation& sim, const server::objects::ObjectSet& objects) {
        const Eigen::Vector3d b = objects.balloons->balloons().at(0).position_enu_m;
        const Eigen::Vector3d cam = b + Eigen::Vector3d(-9.9, -1.0, -1.2);
        const Eigen::Vector3d to_b = b - cam;
        server::physics::set_mocap_pose(sim.world(), sim.world().body_id("uav0_gimbal"), cam,
                                        look(std::atan2(to_b.y(), to_b.x()) + 0.05,
                                             std::atan2(to_b.z(), to_b.head<2>().norm())));
        server::physics::set_vehicle_state(sim.world(), 1, cam + Eigen::Vector3d(6.0, 1.5, 0.0),
                                           Eigen::Quaterniond::Identity(), Eigen::Vector3d::Zero(),
                                           Eigen::Vector3d::Zero());
      });
  BalloonDetector detector({}, frame.intrinsics);
  if (detector.detect(frame.bgr).empty()) state.SkipWithError("no balloon in the rendered frame");
  for (auto _ : state) benchmark::DoNotOptimize(detector.detect(frame.bgr));
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK_CAPTURE(BM_BalloonDetectRendered, 320x240, 320, 240)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_BalloonDetectRendered, 640x480, 640, 480)->Unit(benchmark::kMillisecond);

// mbzirc2017.xml, the hexa's down camera (fovy 60 deg) 10 m above the deck of the truck 5 s into
// its drive, 1.5 m off to the side, tilted 6 deg with the vehicle
void BM_MarkerDetectRendered(benchmark::State& state, int width, int height) {
  namespace server = uavsim::server;
  const RenderedFrame frame = render_world(
      "mbzirc2017.xml", "uav0_down", width, height,
      [](server::sim::Simulation& sim, const server::objects::ObjectSet& objects) {
        sim.run_until(5.0);
        objects.trucks.at(0)->before_step(sim);
        const Eigen::Vector3d deck = objects.trucks.at(0)->state(sim.time_s()).deck_centre_enu_m;
        const Eigen::Quaterniond tilt = q_enu_body_from_rpy(0.06, -0.08, 0.3);
        server::physics::set_mocap_pose(sim.world(), sim.world().body_id("uav0_gimbal"),
                                        deck + Eigen::Vector3d(1.0, -1.1, 10.0),
                                        tilt * look(0.0, -kPi / 2));
      });
  MarkerDetector detector;
  if (!detector.detect(frame.bgr)) state.SkipWithError("no marker in the rendered frame");
  for (auto _ : state) benchmark::DoNotOptimize(detector.detect(frame.bgr));
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK_CAPTURE(BM_MarkerDetectRendered, 320x240, 320, 240)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_MarkerDetectRendered, 640x480, 640, 480)->Unit(benchmark::kMillisecond);

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
