// Camera rendering throughput: CameraRenderer vs bare MuJoCo + OSMesa, same scene and backend.
//   BM_RenderCamera/WxH/cams:N       CameraRenderer::render for N cameras (RGB8, top row first)
//   BM_BareMujocoRender/WxH/cams:N   mjv_updateScene + mjr_render + mjr_readPixels, same flags
//   BM_RenderVsBarePaired/WxH        both, alternating frame by frame; counters give the ratio
//   BM_BareMujocoRenderDefaults/WxH  bare, MuJoCo's defaults (shadows, reflections, skybox, MSAA)
// Counter fps: frames (all cameras together) per second of wall time, not the CPU time that the
// "CPU" column shows, because llvmpipe rasterises on its own threads.
#include <benchmark/benchmark.h>
#include <mujoco/mujoco.h>

#include <chrono>
#include <cstdio>
#include <fstream>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "render/camera_renderer.hpp"
#include "render/gl_context.hpp"

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

struct Scene {
  mjModel* m = nullptr;
  mjData* d = nullptr;
  Scene() {
    const std::string path = "/tmp/uavsim_render_bench.xml";
    std::ofstream(path) << kSceneXml;
    char error[1000] = "";
    m = mj_loadXML(path.c_str(), nullptr, error, sizeof(error));
    if (m == nullptr) throw std::runtime_error(std::string("render_bench: ") + error);
    d = mj_makeData(m);
    mj_forward(m, d);
  }
  ~Scene() {
    mj_deleteData(d);
    mj_deleteModel(m);
  }
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
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
