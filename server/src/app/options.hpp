// Command-line options of uavsim-server.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace uavsim::server::app {

struct Options {
  std::string world_path;
  std::string models_dir;             // empty: the built-in default
  std::optional<std::string> write_world_path;
  uint64_t seed = 1;
  double physics_hz = 1000.0;
  double control_hz = 500.0;
  double rate = 1.0;                  // real time x rate; 0 = as fast as possible
  double duration_s = 0.0;            // 0 = run until interrupted
  bool demo = false;                  // fly the scripted demo on vehicle 0 and exit
  bool quiet = false;
  int api_port = 5700;                // sim socket API (docs/protocol.md); 0 = ephemeral; -1 = none
  std::string api_bind_address = "127.0.0.1";
  double lockstep_timeout_s = 10.0;   // wall seconds a lockstep client may take for one tick
  int mavlink_base_port = 5760;       // vehicle i: base + 10 i; 0 = ephemeral; -1 = no MAVLink endpoints
  std::string bind_address = "127.0.0.1";
  std::optional<std::array<uint8_t, 32>> mavlink_key;  // --mavlink-key HEX64: MAVLink 2 signing from the start
  std::vector<std::string> camera_overrides;  // --camera CAMNAME:key=value,... (repeatable)
  bool cameras = true;                        // --no-cameras: no renderer (camera ops answer not_available)
  std::optional<std::string> record_path;     // --record out.mp4
  double record_fps = 15.0;
  int record_width = 640;
  int record_height = 480;
};

// Parses argv. Returns std::nullopt after printing --help or an error (exit_code says which).
std::optional<Options> parse_options(int argc, char** argv, int* exit_code);
const char* usage();

}  // namespace uavsim::server::app
