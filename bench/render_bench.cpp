// Camera rendering throughput: CameraRenderer vs bare MuJoCo + OSMesa, same scene and backend.
//   BM_RenderCamera/WxH/cams:N       CameraRenderer::render for N cameras (RGB8, top row first)
//   BM_BareMujocoRender/WxH/cams:N   mjv_updateScene + mjr_render + mjr_readPixels, same flags
//   BM_RenderVsBarePaired/WxH        both, alternating frame by frame; counters give the ratio
//   BM_BareMujocoRenderDefaults/WxH  bare, MuJoCo's defaults (shadows, reflections, skybox, MSAA)
//   BM_Cameras/B/WxH/cams:N/threads:T  the frame service (issue 17, "Cameras"): N cameras (1, 4,
//   16),
//                                    backend B (osmesa, egl), T render threads (1: serial; more:
//                                    the cameras split over T threads, each with its own GL
//                                    context); this thread plays the loop thread: capture at each
//                                    frame instant, then wait until every camera's RGB frame
//                                    reached a consumer
//   BM_CamerasPaired/A_vs_B/WxH        two such frame services, A and B (backend:cameras:threads),
//   frame
//                                    instant by frame instant in one loop, so that the load of
//                                    other processes on a shared machine falls on both alike:
//                                    a_fps_per_camera, b_fps_per_camera and ratio = b / a (per
//                                    camera)
// Counter fps: frames (all cameras together) per second of wall time, not the CPU time that the
// "CPU" column shows, because llvmpipe rasterises on its own threads; fps_per_camera = fps / N.
// llvmpipe starts LP_NUM_THREADS rasteriser threads per context (default: one per CPU), read once
// per process: compare LP_NUM_THREADS settings by running the bench once with each.
// Both backends in one process: on Mesa they share one GL dispatch, so MuJoCo's entry points (taken
// once, from the first backend that renders: gl_context.hpp) serve both in any order.
#include <benchmark/benchmark.h>
#include <mujoco/mujoco.h>

#include <chrono>
#include <cstdio>
#include <memory>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "../tests/support/mjcf_scene.hpp"
#include "render/camera_renderer.hpp"
#include "render/camera_setup.hpp"
#include "render/frame_service.hpp"
#include "render/gl_context.hpp"
#include "uavsim/common/angles.hpp"

namespace {

using uavsim::server::render::CameraConfig;
using uavsim::server::render::CameraFrame;
using uavsim::server::render::CameraRenderer;

// an outdoor-like scene: textured ground, sky, a sun that casts shadows, a quad-sized body and some
// clutter, seen by four cameras from different places
constexpr char kSceneXml[] = R"(
<mujoco>
  <visual>
    <global offwidth="640" offheight="480"/>
    <quality shadowsize="2048"/>
  </visual>
  <asset>
    <texture name="sky" type="skybox" builtin="gradient" rgb1="0.4 0.6 0.8" rgb2="0 0 0" width="256" height="256"/>
    <texture name="grid" type="2d" builtin="checker" rgb1="0.3 0.4 0.3" rgb2="0.2 0.3 0.2" width="512" height="512"/>
    <material name="ground" texture="grid" texrepeat="20 20" reflectance="0.2"/>
  </asset>
  <worldbody>
    <light directional="true" pos="0 0 20" dir="0.3 0.2 -1" castshadow="true"/>
    <geom type="plane" size="50 50 0.1" material="ground"/>
    <camera name="cam0" pos="-8 0 3" xyaxes="0 -1 0 0.3 0 1"/>
    <camera name="cam1" pos="8 0 3" xyaxes="0 1 0 -0.3 0 1"/>
    <camera name="cam2" pos="0 -8 3" xyaxes="1 0 0 0 0.3 1"/>
    <camera name="cam3" pos="0 0 12" xyaxes="1 0 0 0 1 0"/>
    <!-- cam4..cam15 (BM_Cameras): a ring around the quad, each aimed at it -->
    CAMERA_RING
    <body name="quad" pos="0 0 2">
      <freejoint/>
      <geom type="box" size="0.15 0.15 0.04" rgba="0.2 0.2 0.2 1"/>
      <geom type="cylinder" pos="0.25 0.25 0.05" size="0.12 0.005" rgba="0.8 0.8 0.8 0.6"/>
      <geom type="cylinder" pos="-0.25 0.25 0.05" size="0.12 0.005" rgba="0.8 0.8 0.8 0.6"/>
      <geom type="cylinder" pos="0.25 -0.25 0.05" size="0.12 0.005" rgba="0.8 0.8 0.8 0.6"/>
      <geom type="cylinder" pos="-0.25 -0.25 0.05" size="0.12 0.005" rgba="0.8 0.8 0.8 0.6"/>
    </body>
    <geom type="sphere" pos="3 2 3" size="0.4" rgba="0 1 0 1"/>
    <geom type="capsule" fromto="3 2 0 3 2 2.6" size="0.03" rgba="0.5 0.5 0.5 1"/>
    <geom type="sphere" pos="-3 -2 3" size="0.4" rgba="0 1 0 1"/>
    <geom type="capsule" fromto="-3 -2 0 -3 -2 2.6" size="0.03" rgba="0.5 0.5 0.5 1"/>
    <geom type="box" pos="5 -4 0.75" size="2 1 0.75" rgba="0.7 0.1 0.1 1"/>
    <geom type="box" pos="-5 4 0.05" size="0.75 0.75 0.05" rgba="0.9 0.9 0.9 1"/>
  </worldbody>
</mujoco>
)";

constexpr int kMaxCameras = 16;

// cam4..cam15 on a circle of 9 m radius, 2 to 5 m high, looking at the quad
std::string camera_ring() {
  std::string xml;
  for (int c = 4; c < kMaxCameras; ++c) {
    const double a = 2.0 * uavsim::common::kPi * (c - 4) / (kMaxCameras - 4);
    xml += "<camera name=\"cam" + std::to_string(c) + "\" pos=\"" +
           std::to_string(9.0 * std::cos(a)) + " " + std::to_string(9.0 * std::sin(a)) + " " +
           std::to_string(2.0 + (c % 4)) + "\" mode=\"targetbody\" target=\"quad\"/>\n";
  }
  return xml;
}

// the scene with its ring of cameras
std::string scene_xml() {
  std::string xml = kSceneXml;
  xml.replace(xml.find("CAMERA_RING"), std::string("CAMERA_RING").size(), camera_ring());
  return xml;
}

struct Scene : uavsim::testing::MjcfScene {
  Scene() : MjcfScene(scene_xml(), "/tmp/uavsim_render_bench.xml") {}
};

// frames per second of wall time over the timed loop
void report_fps(benchmark::State& state, int cameras, std::chrono::steady_clock::time_point start) {
  const double wall_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  state.counters["fps"] = static_cast<double>(state.iterations()) * cameras / wall_s;
}

Scene& scene() {
  static Scene s;
  return s;
}

void BM_RenderCamera(benchmark::State& state, int width, int height, int cameras) {
  Scene& s = scene();
  std::vector<CameraConfig> configs;
  for (int c = 0; c < cameras; ++c) {
    CameraConfig config;
    config.camera = "cam" + std::to_string(c);
    config.width_px = width;
    config.height_px = height;
    configs.push_back(config);
  }
  CameraRenderer renderer(s.m, configs);
  std::vector<CameraFrame> frames(cameras);
  // warm-up: first frames upload textures and compile shaders
  for (int c = 0; c < cameras; ++c) renderer.render(s.d, c, &frames[c]);
  const auto start = std::chrono::steady_clock::now();
  for (auto _ : state) {
    for (int c = 0; c < cameras; ++c) renderer.render(s.d, c, &frames[c]);
    benchmark::DoNotOptimize(frames[0].pixels.data());
  }
  report_fps(state, cameras, start);
}

// bare MuJoCo on the same GL backend: mjv_updateScene + mjr_render + mjr_readPixels, nothing else;
// fast = the renderer's defaults (no shadows, reflections, skybox, MSAA)
class BareRenderer {
 public:
  BareRenderer(const mjModel* m, int width, int height, bool fast)
      : m_(m),
        gl_(uavsim::server::render::make_gl_context("osmesa")),
        viewport_{0, 0, width, height} {
    if (!gl_->make_current()) throw std::runtime_error("render_bench: make_current failed");
    mjModel model = *m;  // shallow copy: only the sample count differs
    if (fast) model.vis.quality.offsamples = 0;
    mjr_defaultContext(&con_);
    mjr_makeContext(&model, &con_, mjFONTSCALE_50);
    mjv_defaultScene(&scn_);
    mjv_makeScene(m, &scn_, 2000);
    mjv_defaultOption(&opt_);
    if (fast) {
      scn_.flags[mjRND_SHADOW] = 0;
      scn_.flags[mjRND_REFLECTION] = 0;
      scn_.flags[mjRND_SKYBOX] = 0;
    }
    rgb_.resize(static_cast<size_t>(width) * height * 3);
  }
  ~BareRenderer() {
    mjv_freeScene(&scn_);
    gl_->make_current();
    mjr_freeContext(&con_);
    gl_->release();
  }

  void render(mjData* d, int camera_id) {
    gl_->make_current();
    mjvCamera cam;
    mjv_defaultCamera(&cam);
    cam.type = mjCAMERA_FIXED;
    cam.fixedcamid = camera_id;
    mjv_updateScene(m_, d, &opt_, nullptr, &cam, mjCAT_ALL, &scn_);
    mjr_setBuffer(mjFB_OFFSCREEN, &con_);
    mjr_render(viewport_, &scn_, &con_);
    mjr_readPixels(rgb_.data(), nullptr, viewport_, &con_);
    benchmark::DoNotOptimize(rgb_.data());
  }

 private:
  const mjModel* m_;
  std::unique_ptr<uavsim::server::render::GlContext> gl_;
  mjrRect viewport_;
  mjrContext con_;
  mjvScene scn_;
  mjvOption opt_;
  std::vector<unsigned char> rgb_;
};

void BM_BareMujocoRender(benchmark::State& state, int width, int height, int cameras, bool fast) {
  Scene& s = scene();
  BareRenderer bare(s.m, width, height, fast);
  for (int c = 0; c < cameras; ++c) bare.render(s.d, c);  // warm-up
  const auto start = std::chrono::steady_clock::now();
  for (auto _ : state) {
    for (int c = 0; c < cameras; ++c) bare.render(s.d, c);
  }
  report_fps(state, cameras, start);
}

// CameraRenderer and bare MuJoCo frame by frame in one loop, so that load from other processes on a
// shared machine falls on both alike; each side's time includes switching to its GL context
void BM_RenderVsBarePaired(benchmark::State& state, int width, int height) {
  Scene& s = scene();
  CameraConfig config;
  config.camera = "cam0";
  config.width_px = width;
  config.height_px = height;
  CameraRenderer renderer(s.m, {config});
  BareRenderer bare(s.m, width, height, true);
  CameraFrame frame;
  renderer.render(s.d, 0, &frame);  // warm-up
  bare.render(s.d, 0);
  using Clock = std::chrono::steady_clock;
  Clock::duration renderer_time{}, bare_time{};
  for (auto _ : state) {
    const auto t0 = Clock::now();
    renderer.render(s.d, 0, &frame);
    const auto t1 = Clock::now();
    bare.render(s.d, 0);
    renderer_time += t1 - t0;
    bare_time += Clock::now() - t1;
  }
  const double n = static_cast<double>(state.iterations());
  const double renderer_fps = n / std::chrono::duration<double>(renderer_time).count();
  const double bare_fps = n / std::chrono::duration<double>(bare_time).count();
  state.counters["renderer_fps"] = renderer_fps;
  state.counters["bare_fps"] = bare_fps;
  state.counters["ratio"] = renderer_fps / bare_fps;
}

namespace render = uavsim::server::render;

// wants every frame as RGB and must have it (lockstep): the frame service never drops one
class RgbConsumer : public render::FrameConsumer {
 public:
  void want(int, int64_t, int64_t, std::vector<render::EncodingKey>* encodings,
            bool* must) override {
    encodings->push_back({render::Encoding::kRgb, 0});
    *must = true;
  }
  void dropped(int, int64_t) override {}
  void deliver(const render::ReadyFrame& f) override {
    benchmark::DoNotOptimize(f.image({render::Encoding::kRgb, 0}));
  }
};

// cameras cam0.. of the bench scene, each as if a different vehicle's, all due every frame instant
std::unique_ptr<render::FrameService> camera_service(const Scene& s, const std::string& backend,
                                                     int width, int height, int cameras,
                                                     int threads, double fps) {
  std::vector<render::CameraSetup> setups;
  for (int c = 0; c < cameras; ++c) {
    render::CameraSetup setup;
    setup.config.camera = "cam" + std::to_string(c);
    setup.config.width_px = width;
    setup.config.height_px = height;
    setup.config.fps_hz = fps;
    setup.vehicle = c;
    setups.push_back(setup);
  }
  render::FrameServiceOptions options;
  options.backend = backend;
  options.render_threads = threads;
  options.queue_depth = 1;
  return std::make_unique<render::FrameService>(s.m, setups, options);
}

constexpr double kInstantsPerSimSecond = 10.0;  // frame period of every camera: 0.1 s of sim time

// one frame instant: every camera due, rendered and delivered (lockstep) before it returns
std::chrono::steady_clock::duration frame_instant(const Scene& s, render::FrameService& service,
                                                  double t) {
  const auto t0 = std::chrono::steady_clock::now();
  s.d->time = t;
  service.capture(s.d);
  service.wait_delivered();
  return std::chrono::steady_clock::now() - t0;
}

void BM_Cameras(benchmark::State& state, const std::string& backend, int width, int height,
                int cameras, int threads) {
  Scene& s = scene();
  const auto service =
      camera_service(s, backend, width, height, cameras, threads, kInstantsPerSimSecond);
  RgbConsumer consumer;
  service->add_consumer(&consumer);
  double t = 0.0;
  // warm-up: shaders, textures, first allocations
  for (int k = 0; k < 3; ++k, t += 1.0 / kInstantsPerSimSecond) frame_instant(s, *service, t);
  const auto start = std::chrono::steady_clock::now();
  for (auto _ : state) {
    frame_instant(s, *service, t);
    t += 1.0 / kInstantsPerSimSecond;
  }
  report_fps(state, cameras, start);
  state.counters["fps_per_camera"] = state.counters["fps"] / cameras;
  state.counters["threads"] = service->render_threads();
}

// one of the two sides of BM_CamerasPaired
struct ServiceSpec {
  std::string backend;
  int cameras = 1;
  int threads = 1;
  std::string name() const {
    return backend + ":" + std::to_string(cameras) + ":" + std::to_string(threads);
  }
};

void BM_CamerasPaired(benchmark::State& state, const ServiceSpec& a, const ServiceSpec& b,
                      int width, int height) {
  Scene& s = scene();
  const auto service_a =
      camera_service(s, a.backend, width, height, a.cameras, a.threads, kInstantsPerSimSecond);
  const auto service_b =
      camera_service(s, b.backend, width, height, b.cameras, b.threads, kInstantsPerSimSecond);
  RgbConsumer consumer;
  service_a->add_consumer(&consumer);
  service_b->add_consumer(&consumer);
  std::chrono::steady_clock::duration time_a{}, time_b{};
  double t = 0.0;
  for (int k = 0; k < 3; ++k, t += 1.0 / kInstantsPerSimSecond) {
    frame_instant(s, *service_a, t);
    frame_instant(s, *service_b, t);
  }
  for (auto _ : state) {
    time_a += frame_instant(s, *service_a, t);
    time_b += frame_instant(s, *service_b, t);
    t += 1.0 / kInstantsPerSimSecond;
  }
  // frame instants per second = frames per second of each camera
  const double n = static_cast<double>(state.iterations());
  const double a_fps = n / std::chrono::duration<double>(time_a).count();
  const double b_fps = n / std::chrono::duration<double>(time_b).count();
  state.counters["a_fps_per_camera"] = a_fps;
  state.counters["b_fps_per_camera"] = b_fps;
  state.counters["ratio"] = b_fps / a_fps;
}

}  // namespace

int main(int argc, char** argv) {
  for (const auto& [w, h] : {std::pair{320, 240}, std::pair{640, 480}}) {
    const std::string size = std::to_string(w) + "x" + std::to_string(h);
    for (int cams : {1, 4}) {
      const std::string suffix = size + "/cams:" + std::to_string(cams);
      benchmark::RegisterBenchmark(("BM_RenderCamera/" + suffix).c_str(), BM_RenderCamera, w, h,
                                   cams)
          ->Unit(benchmark::kMillisecond);
      benchmark::RegisterBenchmark(("BM_BareMujocoRender/" + suffix).c_str(), BM_BareMujocoRender,
                                   w, h, cams, true)
          ->Unit(benchmark::kMillisecond);
    }
    benchmark::RegisterBenchmark(("BM_RenderVsBarePaired/" + size).c_str(), BM_RenderVsBarePaired,
                                 w, h)
        ->Unit(benchmark::kMillisecond);
    benchmark::RegisterBenchmark(("BM_BareMujocoRenderDefaults/" + size).c_str(),
                                 BM_BareMujocoRender, w, h, 1, false)
        ->Unit(benchmark::kMillisecond);
  }
  // BM_Cameras: per backend, size and camera count, serial then parallel
  const int parallel = std::max(2, static_cast<int>(std::thread::hardware_concurrency()));
  for (const std::string backend : {"osmesa", "egl"}) {
    for (const auto& [w, h] : {std::pair{320, 240}, std::pair{640, 480}}) {
      for (int cams : {1, 4, kMaxCameras}) {
        for (int threads : {1, std::min(cams, parallel)}) {
          const std::string name = "BM_Cameras/" + backend + "/" + std::to_string(w) + "x" +
                                   std::to_string(h) + "/cams:" + std::to_string(cams) +
                                   "/threads:" + std::to_string(threads);
          benchmark::RegisterBenchmark(name.c_str(), BM_Cameras, backend, w, h, cams, threads)
              ->Unit(benchmark::kMillisecond)
              ->UseRealTime()
              ->Iterations(cams * w >= kMaxCameras * 640 ? 6 : 20);
          if (cams == 1) break;  // one camera: one thread either way
        }
      }
    }
  }
  // paired: serial vs parallel, OSMesa vs EGL, and the issue's goal (1 camera vs 4, per camera)
  for (const auto& [w, h] : {std::pair{320, 240}, std::pair{640, 480}}) {
    std::vector<std::pair<ServiceSpec, ServiceSpec>> pairs;
    for (const std::string backend : {"osmesa", "egl"}) {
      for (int cams : {4, kMaxCameras}) {
        pairs.push_back({{backend, cams, 1}, {backend, cams, std::min(cams, parallel)}});
      }
      pairs.push_back({{backend, 1, 1}, {backend, 4, std::min(4, parallel)}});
    }
    for (int cams : {1, 4, kMaxCameras}) pairs.push_back({{"osmesa", cams, 1}, {"egl", cams, 1}});
    for (const auto& [a, b] : pairs) {
      const std::string name = "BM_CamerasPaired/" + a.name() + "_vs_" + b.name() + "/" +
                               std::to_string(w) + "x" + std::to_string(h);
      // a fixed count of frame instants: building the services (GL contexts, llvmpipe's shaders)
      // takes longer than the instants, and Google Benchmark would build them again per estimate
      const int instants = std::max(a.cameras, b.cameras) * w >= kMaxCameras * 640 ? 6 : 15;
      benchmark::RegisterBenchmark(name.c_str(), BM_CamerasPaired, a, b, w, h)
          ->Unit(benchmark::kMillisecond)
          ->Iterations(instants);
    }
  }
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
