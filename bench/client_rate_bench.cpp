// The C++ side of bench/python_bench.py (docs/results/python.md): how fast a client_cpp program
// runs against a server that the script started, in the same run as the same measurement from
// Python. A plain program, not a Google Benchmark: it measures one thing against a live server and
// prints one JSON line.
//
//   client_rate_bench --api PORT --mavlink PORT --mode ticks|camera [--seconds S] [--period P]
//                     [--camera NAME] [--modalities M] [--seed N]
//
// Both modes: hold the clock, reset to t = 0 with the seed, join the lockstep with a period of P
// sim seconds, let the clock go, then run the loop for S sim seconds, timing it on the wall clock.
//   ticks:  one Vehicle connected with a telemetry callback (counting updates): lockstep ticks per
//   second. camera: a CameraSubscriber on NAME (BGR; or --modalities "depth+segmentation", any of
//   rgb, depth, segmentation joined by '+') with a callback (counting frames): frames per second.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>

#include "uavsim/client/camera.hpp"
#include "uavsim/client/event_loop.hpp"
#include "uavsim/client/sim_connection.hpp"
#include "uavsim/client/vehicle.hpp"

namespace {

using namespace uavsim::client;

int fail(const std::string& what) {
  std::fprintf(stderr, "client_rate_bench: %s\n", what.c_str());
  return 1;
}

}  // namespace

int main(int argc, char** argv) {
  int api_port = 0, mavlink_port = 0;
  std::string mode = "ticks", camera = "overview", modalities = "rgb";
  double seconds = 10.0, period_s = 0.01;
  unsigned long long seed = 1;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string k = argv[i], v = argv[i + 1];
    if (k == "--api")
      api_port = std::atoi(v.c_str());
    else if (k == "--mavlink")
      mavlink_port = std::atoi(v.c_str());
    else if (k == "--mode")
      mode = v;
    else if (k == "--seconds")
      seconds = std::atof(v.c_str());
    else if (k == "--period")
      period_s = std::atof(v.c_str());
    else if (k == "--camera")
      camera = v;
    else if (k == "--modalities")
      modalities = v;
    else if (k == "--seed")
      seed = std::strtoull(v.c_str(), nullptr, 10);
    else
      return fail("unknown option " + k);
  }
  if (api_port < 1 || api_port > 65535 ||
      (mode == "ticks" && (mavlink_port < 1 || mavlink_port > 65535))) {
    return fail("--api (and for ticks --mavlink) must be ports in 1..65535");
  }
  if (!(seconds > 0.0 && seconds <= 3600.0) || !(period_s > 0.0 && period_s <= 1.0)) {
    return fail("--seconds must be in (0, 3600] and --period in (0, 1]");
  }
  if (mode != "ticks" && mode != "camera") return fail("--mode must be ticks or camera");
  CameraConfig cc;
  cc.camera = camera;
  cc.colour = cc.depth = cc.segmentation = false;
  for (size_t start = 0; start <= modalities.size();) {
    const size_t end = std::min(modalities.find('+', start), modalities.size());
    const std::string m = modalities.substr(start, end - start);
    bool* on = m == "rgb"            ? &cc.colour
               : m == "depth"        ? &cc.depth
               : m == "segmentation" ? &cc.segmentation
                                     : nullptr;
    if (on == nullptr)
      return fail("--modalities: rgb, depth, segmentation joined by '+', not " + modalities);
    *on = true;
    start = end + 1;
  }

  // t = 0 with the seed, the clock held until this program has joined
  auto api = SimConnection::connect("127.0.0.1", static_cast<uint16_t>(api_port));
  if (!api) return fail(api.message());
  if (!(*api)->pause() || !(*api)->reset(seed)) return fail("pause/reset refused");
  auto loop = EventLoop::create(LoopConfig::lockstep("127.0.0.1", api_port, period_s));
  if (!loop) return fail(loop.message());
  if (!(*api)->resume()) return fail("resume refused");

  std::uint64_t telemetry = 0, frames = 0;
  std::unique_ptr<Vehicle> vehicle;
  std::unique_ptr<CameraSubscriber> cam;
  if (mode == "ticks") {
    VehicleConfig vc;
    vc.sim_vehicle = "uav0";
    vehicle = std::make_unique<Vehicle>(**loop, vc);
    if (auto c = vehicle->connect("tcp:127.0.0.1:" + std::to_string(mavlink_port)); !c)
      return fail(c.message());
    vehicle->on_telemetry([&](const Telemetry&) { ++telemetry; });
  } else {
    auto s = CameraSubscriber::subscribe(**loop, cc, [&](const CameraFrame& f) {
      frames += f.image.empty() && f.depth_m.empty() && f.object_ids.empty() ? 0 : 1;
    });
    if (!s) return fail(s.message());
    cam = std::move(*s);
  }

  const double t0 = (*loop)->now();
  const auto w0 = std::chrono::steady_clock::now();
  if (auto r = (*loop)->run_for(seconds); !r) return fail(r.message());
  const double wall_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - w0).count();
  const double sim_s = (*loop)->now() - t0;
  std::printf(
      "{\"mode\": \"%s\", \"sim_s\": %.6f, \"wall_s\": %.6f, \"ticks\": %.0f, \"telemetry\": %llu, "
      "\"frames\": %llu}\n",
      mode.c_str(), sim_s, wall_s, sim_s / period_s, static_cast<unsigned long long>(telemetry),
      static_cast<unsigned long long>(frames));
  return 0;
}
