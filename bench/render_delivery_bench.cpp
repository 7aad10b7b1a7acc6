// Camera frames as an API subscriber receives them vs bare MuJoCo + OSMesa, in models/worlds/mbzirc2020.xml
// (plus a fourth camera), all effects off (shadows, reflections, skybox, MSAA: the cameras' defaults).
//   BM_BareRender/WxH/cams:N      mjv_updateScene + mjr_render + mjr_readPixels per camera, one GL context
//                                 on this thread: the upper bound
//   BM_DeliveredFrames/WxH/cams:N FrameService + ApiServer as server_app wires them; this thread plays the
//                                 loop thread (capture, then the API gate, at each frame instant; the state is
//                                 held, so only rendering and delivery are measured); a reader thread
//                                 subscribes to the N cameras (camera_subscribe, rgb) over loopback and reads
//                                 every frame
// Counters (per second of wall time; llvmpipe rasterises on its own threads, so CPU time means little):
//   fps            bare frames/s (all cameras together)
//   rendered_fps   frames the frame service rendered per second
//   delivered_fps  frames the reader received in full per second
//   ratio          delivered_fps / the bare fps of the same size and camera count, measured earlier in this
//                  run (target >= 0.8). The machine is shared: compare ratios within one run.
#include <arpa/inet.h>
#include <benchmark/benchmark.h>
#include <mujoco/mujoco.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstring>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

#include <nlohmann/json.hpp>

#include "api/api_server.hpp"
#include "physics/world.hpp"
#include "physics/world_composer.hpp"
#include "render/camera_setup.hpp"
#include "render/frame_service.hpp"
#include "render/gl_context.hpp"
#include "sim/simulation.hpp"

namespace {

namespace render = uavsim::server::render;
namespace api = uavsim::server::api;
namespace physics = uavsim::server::physics;
namespace sim = uavsim::server::sim;
using Clock = std::chrono::steady_clock;
using Json = nlohmann::json;

constexpr int kFrameInstants = 120;  // iterations: frame instants, each with a frame of every camera
constexpr int kWarmupInstants = 5;   // not timed: llvmpipe compiles its shaders on the first frames
constexpr double kCameraFps = 30.0;

// mbzirc2020 has three cameras (two quads' front cameras, the overview); a second overview makes four
std::unique_ptr<sim::Simulation> make_world() {
  physics::ComposeOptions o;
  o.models_dir = UAVSIM_MODELS_DIR;
  std::string mjcf = physics::compose_world(std::string(UAVSIM_MODELS_DIR) + "/worlds/mbzirc2020.xml", o);
  const size_t wb = mjcf.find("<worldbody>");
  if (wb == std::string::npos) throw std::runtime_error("render_delivery_bench: no <worldbody>");
  mjcf.insert(wb + 11, R"(<camera name="overview2" pos="0 75 45" xyaxes="-1 0 0 0 -0.5 0.866"/>)");
  auto s = std::make_unique<sim::Simulation>(physics::World::from_mjcf(mjcf, "mbzirc2020+overview2"),
                                             sim::SimConfig{});
  // one second of sim time: vehicles and objects settled, then the state is held
  s->run_until(1.0);
  mj_forward(s->world().model(), s->world().data());
  return s;
}

std::vector<render::CameraSetup> cameras_of(const mjModel* m, int count, int w, int h) {
  std::vector<render::CameraSetup> all = render::discover_cameras(m, {}, {}, 500.0);
  if (static_cast<int>(all.size()) < count) throw std::runtime_error("render_delivery_bench: too few cameras");
  all.resize(static_cast<size_t>(count));
  for (render::CameraSetup& c : all) {
    c.config.width_px = w;
    c.config.height_px = h;
    c.config.fps_hz = kCameraFps;
  }
  return all;
}

// bare fps per (w, h, cameras), for the ratio
std::map<std::tuple<int, int, int>, double>& bare_fps() {
  static std::map<std::tuple<int, int, int>, double> fps;
  return fps;
}

void BM_BareRender(benchmark::State& state, int w, int h, int cams) {
  auto s = make_world();
  const mjModel* m = s->world().model();
  mjData* d = s->world().data();
  const std::vector<render::CameraSetup> setups = cameras_of(m, cams, w, h);
  std::vector<int> ids;
  for (const auto& c : setups) ids.push_back(mj_name2id(m, mjOBJ_CAMERA, c.config.camera.c_str()));

  auto gl = render::make_gl_context("osmesa");
  gl->make_current();
  mjrContext con;
  mjr_defaultContext(&con);
  // no multisampling, as the cameras' default (msaa=0): a shallow model copy that differs only there
  mjModel no_msaa = *m;
  no_msaa.vis.quality.offsamples = 0;
  mjr_makeContext(&no_msaa, &con, mjFONTSCALE_50);
  mjvScene scn;
  mjv_defaultScene(&scn);
  mjv_makeScene(m, &scn, std::max(1000, 2 * m->ngeom));
  mjvOption opt;
  mjv_defaultOption(&opt);
  std::fill(std::begin(opt.sitegroup), std::end(opt.sitegroup), 0);
  opt.flags[mjVIS_RANGEFINDER] = 0;
  std::vector<unsigned char> rgb(static_cast<size_t>(w) * h * 3);
  const mjrRect viewport = {0, 0, w, h};

  auto render_all = [&] {
    for (int id : ids) {
      mjvCamera cam;
      mjv_defaultCamera(&cam);
      cam.type = mjCAMERA_FIXED;
      cam.fixedcamid = id;
      mjv_updateScene(m, d, &opt, nullptr, &cam, mjCAT_ALL, &scn);
      scn.flags[mjRND_SHADOW] = 0;
      scn.flags[mjRND_REFLECTION] = 0;
      scn.flags[mjRND_SKYBOX] = 0;
      mjr_setBuffer(mjFB_OFFSCREEN, &con);
      mjr_render(viewport, &scn, &con);
      mjr_readPixels(rgb.data(), nullptr, viewport, &con);
    }
    benchmark::DoNotOptimize(rgb.data());
  };
  // warm-up: llvmpipe compiles its shaders on the first frames
  for (int i = 0; i < kWarmupInstants; ++i) render_all();
  int64_t frames = 0;
  const auto start = Clock::now();
  for (auto _ : state) {
    render_all();
    frames += cams;
  }
  const double wall_s = std::chrono::duration<double>(Clock::now() - start).count();
  const double fps = frames / wall_s;
  bare_fps()[{w, h, cams}] = fps;
  state.counters["fps"] = fps;
  mjv_freeScene(&scn);
  mjr_freeContext(&con);
  gl->release();
}

// reads the API connection: replies counted, frames read in full and counted
class Reader {
 public:
  Reader(uint16_t port, const std::vector<render::CameraSetup>& cameras) {
    fd_ = socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_port = htons(port);
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    if (connect(fd_, reinterpret_cast<sockaddr*>(&a), sizeof(a)) != 0) throw std::runtime_error("connect");
    std::string requests;
    for (const auto& c : cameras) {
      requests += Json{{"op", "camera_subscribe"}, {"camera", c.config.camera}, {"format", "rgb"}}.dump() + "\n";
    }
    ::send(fd_, requests.data(), requests.size(), MSG_NOSIGNAL);
    thread_ = std::thread([this] { run(); });
  }
  ~Reader() {
    stop_ = true;
    thread_.join();
    close(fd_);
  }
  int replies() const { return replies_.load(); }
  int64_t frames() const { return frames_.load(); }
  Clock::time_point last_frame() const { return Clock::time_point(Clock::duration(last_frame_ns_.load())); }

 private:
  void run() {
    std::string buf;
    std::vector<char> chunk(1 << 20);
    size_t skip = 0;  // image bytes still to read
    while (!stop_) {
      pollfd p{fd_, POLLIN, 0};
      if (poll(&p, 1, 50) <= 0) continue;
      const ssize_t n = recv(fd_, chunk.data(), chunk.size(), 0);
      if (n <= 0) return;
      size_t off = 0;
      const size_t len = static_cast<size_t>(n);
      while (off < len) {
        if (skip > 0) {
          const size_t take = std::min(skip, len - off);
          skip -= take;
          off += take;
          if (skip == 0) {
            ++frames_;
            last_frame_ns_ = Clock::now().time_since_epoch().count();
          }
          continue;
        }
        const char* nl = static_cast<const char*>(memchr(chunk.data() + off, '\n', len - off));
        if (nl == nullptr) {
          buf.append(chunk.data() + off, len - off);
          break;
        }
        buf.append(chunk.data() + off, static_cast<size_t>(nl - (chunk.data() + off)));
        off = static_cast<size_t>(nl - chunk.data()) + 1;
        const Json j = Json::parse(buf, nullptr, false);
        buf.clear();
        if (j.is_object() && j.value("event", "") == "frame") {
          skip = j["bytes"].get<size_t>();
        } else if (j.is_object() && j.contains("ok")) {
          ++replies_;
        }
      }
    }
  }
  int fd_ = -1;
  std::thread thread_;
  std::atomic<bool> stop_{false};
  std::atomic<int> replies_{0};
  std::atomic<int64_t> frames_{0};
  std::atomic<int64_t> last_frame_ns_{0};
};

void BM_DeliveredFrames(benchmark::State& state, int w, int h, int cams) {
  auto s = make_world();
  mjData* d = s->world().data();
  const std::vector<render::CameraSetup> setups = cameras_of(s->world().model(), cams, w, h);
  render::FrameService frames(s->world().model(), setups);
  api::ApiConfig config;
  config.port = 0;
  api::ApiServer server(*s, nullptr, {}, config);
  server.set_frame_service(&frames);
  server.start();
  const auto gate = server.gate();
  const double held_time_s = d->time;

  // the subscriptions run in the gate, as on the loop thread
  Reader reader(server.port(), setups);
  const auto deadline = Clock::now() + std::chrono::seconds(10);
  while (reader.replies() < cams && Clock::now() < deadline) {
    gate(d->time);
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  if (reader.replies() < cams) {
    state.SkipWithError("subscriptions not answered");
    return;
  }

  // frame instant k: every camera due; capture, serve the gate, and keep at most one snapshot in flight
  int64_t k = 0;
  auto instant = [&] {
    ++k;
    d->time = held_time_s + static_cast<double>(k) / kCameraFps;
    frames.capture(d);
    gate(d->time);
    frames.wait_delivered();
  };
  for (int i = 0; i < kWarmupInstants; ++i) instant();
  while (reader.frames() < k * cams && Clock::now() < deadline) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  const render::FrameServiceStats before = frames.stats();
  const int64_t received_before = reader.frames();
  const int64_t k_before = k;
  const auto start = Clock::now();
  for (auto _ : state) instant();
  k -= k_before;
  // the last frames still on their way to the reader
  const int64_t expected = received_before + k * cams;
  const auto drain_end = Clock::now() + std::chrono::seconds(5);
  while (reader.frames() < expected && Clock::now() < drain_end) {
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  const auto rendered_end = Clock::now();
  const double wall_s = std::chrono::duration<double>(reader.last_frame() - start).count();
  const render::FrameServiceStats after = frames.stats();
  const double rendered = static_cast<double>(after.frames_rendered - before.frames_rendered);
  const double delivered = static_cast<double>(reader.frames() - received_before);
  state.counters["rendered_fps"] = rendered / std::chrono::duration<double>(rendered_end - start).count();
  state.counters["delivered_fps"] = wall_s > 0 ? delivered / wall_s : 0.0;
  state.counters["lost"] = static_cast<double>(k * cams) - delivered;
  auto bare = bare_fps().find({w, h, cams});
  if (bare != bare_fps().end() && wall_s > 0) state.counters["ratio"] = delivered / wall_s / bare->second;
  server.shutdown();
}

void register_all() {
  const std::vector<std::pair<int, int>> sizes = {{320, 240}, {640, 480}};
  for (const auto& [w, h] : sizes) {
    for (int cams : {1, 4}) {
      const std::string tag = "/" + std::to_string(w) + "x" + std::to_string(h) + "/cams:" + std::to_string(cams);
      benchmark::RegisterBenchmark(("BM_BareRender" + tag).c_str(), BM_BareRender, w, h, cams)
          ->Iterations(kFrameInstants)
          ->Unit(benchmark::kMillisecond)
          ->UseRealTime();
      benchmark::RegisterBenchmark(("BM_DeliveredFrames" + tag).c_str(), BM_DeliveredFrames, w, h, cams)
          ->Iterations(kFrameInstants)
          ->Unit(benchmark::kMillisecond)
          ->UseRealTime();
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  register_all();
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
