// Camera rendering throughput: CameraRenderer against bare MuJoCo + OSMesa on the same scene and GL
// backend.
//   BM_RenderCamera/<w>x<h>/cams:<n>       CameraRenderer::render for n cameras (frame = RGB8, top
//   row first) BM_BareMujocoRender/<w>x<h>/cams:<n>   mjv_updateScene + mjr_render +
//   mjr_readPixels, same flags BM_BareMujocoRenderDefaults/<w>x<h>    the same with MuJoCo's
//   defaults (shadows, reflections, skybox, 4x MSAA)
// Counter fps: frames rendered per second of wall time (all cameras together); real time, because
// llvmpipe rasterises on its own threads.
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

// bare MuJoCo on the same GL backend; fast = the renderer's defaults (no shadows, reflections,
// skybox, MSAA)
void BM_BareMujocoRender(benchmark::State& state, int width, int height, int cameras, bool fast) {
  Scene& s = scene();
  auto gl = uavsim::server::render::make_gl_context("osmesa");
  if (!gl->make_current()) {
    state.SkipWithError("make_current failed");
    return;
  }
  mjModel model = *s.m;  // shallow copy: only the sample count differs
  if (fast) model.vis.quality.offsamples = 0;
  mjrContext con;
  mjr_defaultContext(&con);
  mjr_makeContext(&model, &con, mjFONTSCALE_50);
  mjvScene scn;
  mjv_defaultScene(&scn);
  mjv_makeScene(s.m, &scn, 2000);
  mjvOption opt;
  mjv_defaultOption(&opt);
  if (fast) {
    scn.flags[mjRND_SHADOW] = 0;
    scn.flags[mjRND_REFLECTION] = 0;
    scn.flags[mjRND_SKYBOX] = 0;
  }
  std::vector<unsigned char> rgb(static_cast<size_t>(width) * height * 3);
  const mjrRect viewport = {0, 0, width, height};
  mjr_setBuffer(mjFB_OFFSCREEN, &con);
  auto render_all = [&] {
    for (int c = 0; c < cameras; ++c) {
      mjvCamera cam;
      mjv_defaultCamera(&cam);
      cam.type = mjCAMERA_FIXED;
      cam.fixedcamid = c;
      mjv_updateScene(s.m, s.d, &opt, nullptr, &cam, mjCAT_ALL, &scn);
      mjr_render(viewport, &scn, &con);
      mjr_readPixels(rgb.data(), nullptr, viewport, &con);
    }
  };
  render_all();  // warm-up
  const auto start = std::chrono::steady_clock::now();
  for (auto _ : state) {
    render_all();
    benchmark::DoNotOptimize(rgb.data());
  }
  report_fps(state, cameras, start);
  mjv_freeScene(&scn);
  mjr_freeContext(&con);
  gl->release();
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
    benchmark::RegisterBenchmark(("BM_BareMujocoRenderDefaults/" + size).c_str(),
                                 BM_BareMujocoRender, w, h, 1, false)
        ->Unit(benchmark::kMillisecond);
  }
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
