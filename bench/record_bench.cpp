// What uavsim-server --record costs, and that nothing of it runs without it:
// models/worlds/mbzirc2020.xml, both quads taking off to 5 m and hovering (posted to their flight
// controllers as in the follow-camera test), run as fast as possible; each iteration is one second
// of sim time (400 control steps).
//   BM_Run/no_cameras         the loop alone (no frame service: uavsim-server --no-cameras, or no
//   API and
//                             no --record)
//   BM_Run/idle_cameras       + the frame service capturing at every control step with nobody
//   wanting a
//                             frame: a launcher's server with --no-record (the API is up, no
//                             subscriber)
//   BM_Run/record_single      + --record --record-camera follow: director, overlay (recording.hpp),
//                             frames to a sink that drops them (the encoder is ffmpeg's, another
//                             process)
//   BM_Run/record_tiled       + --record-layout tiled: the two front cameras rendered and tiled
// Counters: sim_x (sim seconds per wall second) and ratio (wall time per sim second over
// no_cameras's, measured earlier in this run). llvmpipe renders on its own threads, so wall time is
// what counts. The machine is shared: compare ratios within one run.
#include <benchmark/benchmark.h>

#include <atomic>
#include <chrono>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "api/overlay_ops.hpp"
#include "app/camera_owners.hpp"
#include "app/hover_all.hpp"
#include "app/recording.hpp"
#include "app/run_reporter.hpp"
#include "objects/world_objects.hpp"
#include "physics/world.hpp"
#include "render/camera_setup.hpp"
#include "render/frame_service.hpp"
#include "render/video_recorder.hpp"
#include "sim/runner.hpp"
#include "sim/simulation.hpp"

namespace {

namespace app = uavsim::server::app;
namespace api = uavsim::server::api;
namespace render = uavsim::server::render;
namespace physics = uavsim::server::physics;
namespace objects = uavsim::server::objects;
namespace sim = uavsim::server::sim;
using Clock = std::chrono::steady_clock;

enum Variant { kNoCameras, kIdleCameras, kRecordSingle, kRecordTiled };
constexpr double kWarmupS = 3.0;  // take-off and llvmpipe's first frames, not timed

double g_baseline_wall_per_sim_s = 0.0;  // no_cameras of this run

void BM_Run(benchmark::State& state) {
  const auto variant = static_cast<Variant>(state.range(0));
  physics::ComposeOptions co;
  co.models_dir = UAVSIM_MODELS_DIR;
  sim::Simulation s(
      physics::World::load(std::string(UAVSIM_MODELS_DIR) + "/worlds/mbzirc2020.xml", co),
      sim::SimConfig{});
  objects::ObjectSet world_objects = objects::add_world_objects(s);
  app::RunReporter reporter(s, nullptr, nullptr);
  s.schedule().add(sim::Phase::kPostControl, "reporter",
                   [&reporter] { reporter.on_control_step(); });
  api::OverlayOps notes(s);

  // the cameras and the recorder as server_app wires them
  std::unique_ptr<render::FrameService> frames;
  std::unique_ptr<render::VideoRecorder> recorder;
  std::atomic<uint64_t> frames_out{0};
  if (variant != kNoCameras) {
    const render::CameraOwners owners = app::camera_owners(s.world(), world_objects);
    const std::vector<std::string> overrides{"uav0_front:width=384,height=216,fps=15",
                                             "uav1_front:width=384,height=216,fps=15"};
    std::vector<render::CameraSetup> cameras =
        render::discover_cameras(s.world().model(), owners, overrides, 1.0 / s.control_dt_s());
    const size_t cam = *app::record_camera(cameras, "follow");
    cameras[cam].config.fps_hz = 15.0;
    frames = std::make_unique<render::FrameService>(s.world().model(), cameras);
    if (variant == kRecordSingle || variant == kRecordTiled) {
      render::RecorderOptions ro;
      ro.lossless = true;
      ro.sink = [&frames_out](const std::string&, int, int) { ++frames_out; };
      if (variant == kRecordTiled) {
        for (size_t i = 0; i < frames->cameras().size(); ++i) {
          if (frames->cameras()[i].vehicle >= 0) ro.tiles.push_back(static_cast<int>(i));
        }
      }
      recorder = std::make_unique<render::VideoRecorder>(*frames, static_cast<int>(cam), "",
                                                         std::move(ro));
      frames->add_consumer(recorder.get());
      std::vector<int> bodies;
      for (const auto& v : s.world().vehicles()) bodies.push_back(v.body_id);
      frames->set_tracked_bodies(bodies);
      frames->set_director(static_cast<int>(cam),
                           app::record_director("follow", frames->cameras()[cam], s));
      recorder->set_overlay(app::record_overlay_source(s, world_objects, reporter, notes));
    }
  }

  // both quads: GUIDED, arm, take off to 5 m once pre-arm passes (uavsim-server --hover 5)
  app::HoverAll hover(5.0, std::cout, /*quiet=*/true);
  s.schedule().add(sim::Phase::kPostControl, "launch", [&hover, &s] { hover.on_control_step(s); });
  sim::Runner runner(s, 0.0);
  render::FrameService* fs = frames.get();
  if (fs != nullptr) {
    runner.add_gate(sim::Phase::kCapture, "frames",
                    [fs, &s](double) { fs->capture(s.world().data()); });
  }
  runner.run_until(kWarmupS);
  if (fs != nullptr) fs->wait_delivered();

  double t_s = kWarmupS;
  double wall_s = 0.0;
  int64_t sim_seconds = 0;
  for (auto _ : state) {
    const auto start = Clock::now();
    t_s += 1.0;
    runner.run_until(t_s);
    if (fs != nullptr) fs->wait_delivered();
    wall_s += std::chrono::duration<double>(Clock::now() - start).count();
    ++sim_seconds;
  }
  const double wall_per_sim_s = wall_s / static_cast<double>(sim_seconds);
  if (variant == kNoCameras) g_baseline_wall_per_sim_s = wall_per_sim_s;
  state.counters["sim_x"] = 1.0 / wall_per_sim_s;
  if (g_baseline_wall_per_sim_s > 0)
    state.counters["ratio"] = wall_per_sim_s / g_baseline_wall_per_sim_s;
  if (recorder) state.counters["frames"] = static_cast<double>(frames_out.load());
  frames.reset();  // the renderer stops before the recorder goes
  if (recorder) recorder->finish();
}

BENCHMARK(BM_Run)
    ->ArgName("variant")
    ->Arg(kNoCameras)
    ->Arg(kIdleCameras)
    ->Arg(kRecordSingle)
    ->Arg(kRecordTiled)
    ->Iterations(20)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
