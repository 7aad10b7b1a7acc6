// What depth and segmentation cost beside colour (issue 33, docs/results/cameras.md): the frame
// service on the MBZIRC 2020 world's overview camera (ground, arena, five balloons on poles, two
// quads), one render thread, this thread playing the loop thread (capture at a frame instant, then
// wait until the frame reached the consumer: render, read-back, encoding).
//   BM_CameraModalities/WxH  every iteration takes one frame of each variant in turn, so the load
//   of
//                            other processes falls on all of them alike; counters: fps_VARIANT
//                            (frames per second of wall time) and ratio_VARIANT = fps_VARIANT /
//                            fps_rgb.
//   Variants: rgb (colour alone, the reference), rgb_colour_camera (colour alone from the same camera
//   configured without depth and segmentation, in a frame service of its own: what a colour camera
//   pays for the feature), grey, depth, segmentation, depth+segmentation (one geometry pass for both),
//   rgb+depth+segmentation (a capture with everything).
#include <benchmark/benchmark.h>
#include <mujoco/mujoco.h>

#include <chrono>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "physics/world.hpp"
#include "render/camera_setup.hpp"
#include "render/frame_service.hpp"

namespace {

using uavsim::server::physics::ComposeOptions;
using uavsim::server::physics::World;
namespace render = uavsim::server::render;
using render::Encoding;
using render::EncodingKey;

struct Variant {
  std::string name;
  std::vector<EncodingKey> keys;
  bool colour_camera = false;  // the same camera configured without depth and segmentation
};

const std::vector<Variant> kVariants = {
    {"rgb", {{Encoding::kRgb, 0}}},
    {"rgb_colour_camera", {{Encoding::kRgb, 0}}, true},
    {"grey", {{Encoding::kGrey, 0}}},
    {"depth", {{Encoding::kDepth, 0}}},
    {"segmentation", {{Encoding::kSegmentation, 0}}},
    {"depth+segmentation", {{Encoding::kDepth, 0}, {Encoding::kSegmentation, 0}}},
    {"rgb+depth+segmentation",
     {{Encoding::kRgb, 0}, {Encoding::kDepth, 0}, {Encoding::kSegmentation, 0}}},
};

// wants the current variant's images of every frame, lockstep (never dropped)
class Consumer : public render::FrameConsumer {
 public:
  void want(int, int64_t, int64_t, std::vector<EncodingKey>* e, bool* must) override {
    e->insert(e->end(), keys->begin(), keys->end());
    *must = true;
  }
  void dropped(int, int64_t) override {}
  void deliver(const render::ReadyFrame& f) override {
    for (const auto& [key, bytes] : f.images) benchmark::DoNotOptimize(bytes->data());
  }
  const std::vector<EncodingKey>* keys = &kVariants[0].keys;
};

constexpr double kFps = 100.0;  // a frame at every capture below (one per 1/kFps of sim time)

void BM_CameraModalities(benchmark::State& state, int width, int height) {
  ComposeOptions co;
  co.models_dir = UAVSIM_MODELS_DIR;
  const auto world = World::load(std::string(UAVSIM_MODELS_DIR) + "/worlds/mbzirc2020.xml", co);
  mjData* d = world->data();
  mj_forward(world->model(), d);
  const std::string size = "width=" + std::to_string(width) + ",height=" + std::to_string(height);
  // the overview camera alone, with the modalities given, in a frame service of its own
  auto service_for = [&](const std::string& modalities) {
    std::vector<render::CameraSetup> cameras;
    for (const render::CameraSetup& c : render::discover_cameras(
             world->model(), {}, {"overview:" + size + ",fps=100,modalities=" + modalities}, kFps)) {
      if (c.config.camera == "overview") cameras.push_back(c);
    }
    render::FrameServiceOptions options;
    options.render_threads = 1;
    options.queue_depth = 1;
    return std::make_unique<render::FrameService>(world->model(), cameras, options);
  };
  const auto all = service_for("rgb+grey+depth+segmentation");
  const auto colour = service_for("rgb+grey");
  Consumer consumer;
  all->add_consumer(&consumer);
  colour->add_consumer(&consumer);

  double t = 0.0;
  auto frame = [&](const Variant& v) {
    consumer.keys = &v.keys;
    render::FrameService& service = v.colour_camera ? *colour : *all;
    const auto t0 = std::chrono::steady_clock::now();
    d->time = t;
    service.capture(d);
    service.wait_delivered();
    t += 1.0 / kFps;
    return std::chrono::steady_clock::now() - t0;
  };
  // warm-up: every variant's shaders and buffers
  for (int k = 0; k < 2; ++k) {
    for (const Variant& v : kVariants) frame(v);
  }
  std::vector<std::chrono::steady_clock::duration> spent(
      kVariants.size(), std::chrono::steady_clock::duration::zero());
  int64_t rounds = 0;
  for (auto _ : state) {
    for (size_t i = 0; i < kVariants.size(); ++i) spent[i] += frame(kVariants[i]);
    ++rounds;
  }
  const double rgb_fps = rounds / std::chrono::duration<double>(spent[0]).count();
  for (size_t i = 0; i < kVariants.size(); ++i) {
    const double fps = rounds / std::chrono::duration<double>(spent[i]).count();
    state.counters["fps_" + kVariants[i].name] = fps;
    state.counters["ratio_" + kVariants[i].name] = fps / rgb_fps;
  }
  state.SetItemsProcessed(rounds * static_cast<int64_t>(kVariants.size()));
}

}  // namespace

int main(int argc, char** argv) {
  for (const auto& [w, h] : std::vector<std::pair<int, int>>{{640, 480}, {384, 216}}) {
    benchmark::RegisterBenchmark(
        ("BM_CameraModalities/" + std::to_string(w) + "x" + std::to_string(h)).c_str(),
        BM_CameraModalities, w, h)
        ->Unit(benchmark::kMillisecond)
        ->UseRealTime();
  }
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
