#include "app/options.hpp"

#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <string>

namespace uavsim::server::app {

const char* usage() {
  return R"(usage: uavsim-server WORLD.xml [options]

Simulates the world and its vehicles. WORLD.xml is MuJoCo MJCF plus uavsim's <uavsim_vehicle>,
<uavsim_grid> and <uavsim_object> elements (models/README.md).

options:
  --seed N            seed of every random generator (sensor noise, ...); default 1
  --physics-hz HZ     physics rate; default 1000
  --control-hz HZ     flight-control rate, rounded to a divisor of the physics rate; default 500
  --rate X            clock: X times real time (default 1); --rate 0 or --fast: as fast as possible
  --fast              same as --rate 0
  --duration S        stop after S seconds of sim time (default: run until interrupted)
  --demo              fly vehicle 0 through take-off, three waypoints and landing, print what happened,
                      and exit with 0 if the flight succeeded
  --write-world FILE  write the composed MJCF (plain MuJoCo, opens in mujoco-simulate) and exit
  --models-dir DIR    where vehicles/ and objects/ templates live (default: the source tree's models/)
  --mavlink-port BASE TCP port of vehicle 0's MAVLink endpoint; vehicle i listens on BASE + 10 i
                      (ArduPilot SITL's convention); default 5760; 0: ephemeral ports; -1: none
  --bind ADDR         address the MAVLink endpoints listen on; default 127.0.0.1 (loopback only)
  --mavlink-key HEX64 MAVLink 2 signing key (64 hex digits) of every vehicle from the start: frames
                      sent are signed, unsigned ones received are ignored (a client's SETUP_SIGNING
                      replaces it; an all-zero key turns signing off)
  --api-port N        TCP port of the sim socket API (docs/protocol.md); default 5700; 0: an ephemeral
                      port (printed); -1: no API
  --api-bind ADDR     address the sim API listens on; default 127.0.0.1 (loopback only)
  --lockstep-timeout S  drop a lockstep client that takes more than S wall seconds for a tick; default 10
  --camera CAM:K=V,...  camera settings over the world's uavsim:camera:CAM text (CAM * for all):
                      width, height, fps, fovy, shadows, reflections, skybox, msaa (docs/protocol.md)
  --no-cameras        no offscreen renderer (the camera ops answer not_available)
  --record FILE.mp4   write a video of the run from the world camera "overview" (else the first world
                      camera, else the first camera), 15 frames per second of sim time; in real time
                      it drops frames rather than slow physics, at --rate 0 it keeps every frame
  --record-fps F      frames per second of sim time in the video; default 15
  --record-size WxH   video size; default 640x480
  --quiet             print only errors and the result
  --help              this text
)";
}

namespace {

bool parse_double(const std::string& flag, const char* text, double* out) {
  char* end = nullptr;
  const double v = std::strtod(text, &end);
  if (end == text || *end != '\0' || !std::isfinite(v)) {
    std::cerr << "uavsim-server: " << flag << " needs a number, got '" << text << "'\n";
    return false;
  }
  *out = v;
  return true;
}

}  // namespace

std::optional<Options> parse_options(int argc, char** argv, int* exit_code) {
  Options o;
  *exit_code = 2;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&](const char** out) {
      if (i + 1 >= argc) {
        std::cerr << "uavsim-server: " << a << " needs a value\n";
        return false;
      }
      *out = argv[++i];
      return true;
    };
    const char* v = nullptr;
    double number = 0.0;
    if (a == "--help" || a == "-h") {
      std::cout << usage();
      *exit_code = 0;
      return std::nullopt;
    } else if (a == "--seed") {
      if (!value(&v) || !parse_double(a, v, &number) || number < 0) return std::nullopt;
      o.seed = static_cast<uint64_t>(number);
    } else if (a == "--physics-hz") {
      if (!value(&v) || !parse_double(a, v, &o.physics_hz) || o.physics_hz <= 0) return std::nullopt;
    } else if (a == "--control-hz") {
      if (!value(&v) || !parse_double(a, v, &o.control_hz) || o.control_hz <= 0) return std::nullopt;
    } else if (a == "--rate") {
      if (!value(&v) || !parse_double(a, v, &o.rate) || o.rate < 0) return std::nullopt;
    } else if (a == "--fast") {
      o.rate = 0.0;
    } else if (a == "--duration") {
      if (!value(&v) || !parse_double(a, v, &o.duration_s) || o.duration_s < 0) return std::nullopt;
    } else if (a == "--demo") {
      o.demo = true;
    } else if (a == "--write-world") {
      if (!value(&v)) return std::nullopt;
      o.write_world_path = v;
    } else if (a == "--models-dir") {
      if (!value(&v)) return std::nullopt;
      o.models_dir = v;
    } else if (a == "--mavlink-port") {
      if (!value(&v) || !parse_double(a, v, &number) || number < -1 || number > 65535) return std::nullopt;
      o.mavlink_base_port = static_cast<int>(number);
    } else if (a == "--bind") {
      if (!value(&v)) return std::nullopt;
      o.bind_address = v;
    } else if (a == "--mavlink-key") {
      if (!value(&v)) return std::nullopt;
      const std::string hex = v;
      std::array<uint8_t, 32> key{};
      bool ok = hex.size() == 64;
      for (std::size_t k = 0; ok && k < key.size(); ++k) {
        const std::string byte = hex.substr(2 * k, 2);
        char* end = nullptr;
        const unsigned long b = std::strtoul(byte.c_str(), &end, 16);
        ok = std::isxdigit(static_cast<unsigned char>(byte[0])) && end == byte.c_str() + 2;
        key[k] = static_cast<uint8_t>(b);
      }
      if (!ok) {
        std::cerr << "uavsim-server: --mavlink-key needs 64 hex digits (32 bytes)\n";
        return std::nullopt;
      }
      o.mavlink_key = key;
    } else if (a == "--api-port") {
      if (!value(&v) || !parse_double(a, v, &number) || number < -1 || number > 65535) return std::nullopt;
      o.api_port = static_cast<int>(number);
    } else if (a == "--api-bind") {
      if (!value(&v)) return std::nullopt;
      o.api_bind_address = v;
    } else if (a == "--lockstep-timeout") {
      if (!value(&v) || !parse_double(a, v, &o.lockstep_timeout_s) || o.lockstep_timeout_s <= 0) {
        return std::nullopt;
      }
    } else if (a == "--camera") {
      if (!value(&v)) return std::nullopt;
      o.camera_overrides.push_back(v);
    } else if (a == "--no-cameras") {
      o.cameras = false;
    } else if (a == "--record") {
      if (!value(&v)) return std::nullopt;
      o.record_path = v;
    } else if (a == "--record-fps") {
      if (!value(&v) || !parse_double(a, v, &o.record_fps) || o.record_fps <= 0) return std::nullopt;
    } else if (a == "--record-size") {
      if (!value(&v)) return std::nullopt;
      int w = 0, h = 0;
      char x = 0;
      if (std::sscanf(v, "%d%c%d", &w, &x, &h) != 3 || x != 'x' || w <= 0 || h <= 0 || w > 8192 || h > 8192) {
        std::cerr << "uavsim-server: --record-size needs WIDTHxHEIGHT, got '" << v << "'\n";
        return std::nullopt;
      }
      o.record_width = w;
      o.record_height = h;
    } else if (a == "--quiet") {
      o.quiet = true;
    } else if (!a.empty() && a[0] == '-') {
      std::cerr << "uavsim-server: unknown option " << a << " (see --help)\n";
      return std::nullopt;
    } else if (o.world_path.empty()) {
      o.world_path = a;
    } else {
      std::cerr << "uavsim-server: more than one world file given (" << o.world_path << ", " << a << ")\n";
      return std::nullopt;
    }
  }
  if (o.world_path.empty()) {
    std::cerr << "uavsim-server: no world file given\n" << usage();
    return std::nullopt;
  }
  *exit_code = 0;
  return o;
}

}  // namespace uavsim::server::app
