// Command-line options of uavsim-server, and their parser (pure: it prints nothing; main() does).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <string_view>
#include <optional>
#include <string>
#include <vector>

#include "app/render_cameras_option.hpp"

namespace uavsim::server::app {

// One --out option: vehicles' MAVLink streams over UDP, as ArduPilot SITL and mavlink-router do it.
//   udp:HOST:PORT      send to a ground station listening on HOST:PORT and answer what it sends back
//   udpin:ADDR:PORT    listen on ADDR:PORT and answer the first peer that sends
// Without "{i}" vehicle i uses PORT + 10 i; "{i}" anywhere is replaced by the vehicle index instead
// (udp:10.0.0.{i}:14550). "N=" before the URL limits it to vehicle N (and the port is not offset).
struct UdpOut {
  std::string spec;               // the URL, "{i}" unexpanded
  std::optional<int> vehicle;     // "N=..."
};

// One vehicle's UDP target after expansion.
struct UdpTarget {
  bool listen = false;  // udpin
  std::string host;
  int port = 0;
  std::string url() const { return (listen ? "udpin:" : "udp:") + host + ":" + std::to_string(port); }
};

// The target of out for vehicle i: nullopt with an empty *why when out is not for this vehicle,
// nullopt with *why when the URL or the port (PORT + 10 i past 65535) is bad.
std::optional<UdpTarget> udp_target(const UdpOut& out, int vehicle, std::string* why);

// Geodetic position of the world origin (--home LAT,LON,ALT[,0]). SITL's fourth field, the start
// heading, is accepted only as 0: vehicles' headings are their yaw_deg in the world.
struct HomeOption {
  double lat_deg = 0.0;
  double lon_deg = 0.0;
  double alt_m = 0.0;
  double heading_deg = 0.0;
};

// --wind SPEED,DIR_DEG[,GUST]: mean wind speed (m/s), where it blows from (degrees clockwise from north)
// and the turbulence intensity (standard deviation of the gust velocity, m/s).
struct WindOption {
  double speed_m_s = 0.0;
  double from_deg = 0.0;
  std::optional<double> turbulence_sd_m_s;
};

struct Options {
  std::string world_path;
  std::string models_dir;             // empty: the built-in default
  std::optional<std::string> write_world_path;
  uint64_t seed = 1;
  double physics_hz = 1000.0;
  int physics_shards = 1;             // --physics-shards N (1 to 64); 0 = auto
  int physics_threads = 0;            // --physics-threads N; 0 = one per shard, up to the hardware threads
  double control_hz = 500.0;
  double rate = 1.0;                  // real time x rate; 0 = as fast as possible
  double duration_s = 0.0;            // 0 = run until interrupted
  bool demo = false;                  // fly the scripted demo on vehicle 0 and exit
  std::optional<double> hover_m;  // --hover M: every vehicle takes off to M m and holds, no client
  bool quiet = false;
  bool print_schedule = false;        // print the step schedule before the clock starts
  bool version = false;               // --version: print it and exit
  bool list_worlds = false;           // --list-worlds: print the shipped worlds and exit
  int api_port = 5700;                // sim socket API (docs/protocol.md); 0 = ephemeral; -1 = none
  std::string api_bind_address = "127.0.0.1";
  std::optional<std::string> api_token;  // --api-token-file: clients must authenticate first
  bool allow_remote_gcs = false;      // gcs_link_open may target hosts other than the API peer's
  double lockstep_timeout_s = 10.0;   // wall seconds a lockstep client may take for one tick
  double watchdog_s = 10.0;           // a loop without progress this long is reported; 0 = off
  int mavlink_base_port = 5760;       // vehicle i: base + 10 i; 0 = ephemeral; -1 = no MAVLink endpoints
  std::string bind_address = "127.0.0.1";
  std::optional<std::array<uint8_t, 32>> mavlink_key;  // MAVLink 2 signing from the start
  std::vector<UdpOut> udp_outs;       // --out (repeatable); see udp_outs_explicit
  bool udp_outs_explicit = false;     // any --out given (else the default: vehicle 0 to 14550)
  int wait_for_clients = 0;           // hold the clock at 0 until this many clients are connected
  std::optional<std::string> log_dir; // --log-dir: one .tlog per vehicle and events.jsonl
  std::optional<HomeOption> home;     // --home: overrides the world's home
  std::vector<std::string> defaults_files;  // --defaults FILE.parm (repeatable, applied in order)
  std::vector<std::string> camera_overrides;  // --camera CAMNAME:key=value,... (repeatable)
  std::optional<std::string> realism;         // --realism field|ideal: over the world's uavsim:realism
  std::optional<WindOption> wind;             // --wind: over the realism level's and the world's wind
  bool cameras = true;                        // --no-cameras: no renderer (camera ops answer not_available)
  // --render-cameras: rendered with no client (app/camera_floor.hpp)
  std::vector<RenderCamera> render_cameras;
  std::string gl_backend = "osmesa";          // --gl egl|osmesa|auto (render::make_gl_context)
  int render_threads = 0;                     // --render-threads N: camera render threads; 0 = automatic
  std::optional<std::string> record_path;     // --record out.mp4
  double record_fps = 15.0;
  int record_width = 640;
  int record_height = 480;
  std::string record_camera = "overview";     // --record-camera overview|follow|follow:NAME|top|CAMERA
  bool record_overlay = true;                 // --record-overlay 0: frames without the text
  bool record_tiled = false;                  // --record-layout tiled: onboard cameras beside the view
  std::optional<std::string> radio_backend;   // --radio-backend simple|ns3: over the world's uavsim:radio_backend
  // --gcs-link-backend simple|ns3: the GCS link relay's datagrams over ns-3's 802.11 (ns3); over the
  // world's uavsim:gcs_link_backend
  std::optional<std::string> gcs_link_backend;
  std::optional<std::array<double, 3>> gcs_position;  // --gcs-position X,Y,Z: over the world's uavsim:gcs_position
  std::vector<std::string> record_tiles;      // --record-tile CAM[:rgb|depth|segmentation], repeated
};

// What parse_args() decided: run with options, or exit with exit_code after printing output (to
// stdout when exit_code is 0: --help, --version) or error (to stderr, one line saying why).
struct ParseResult {
  std::optional<Options> options;
  int exit_code = 0;
  std::string output;
  std::string error;
};

// Looks up an environment variable (std::getenv in main, a map in tests).
using EnvLookup = std::function<std::optional<std::string>(const std::string& name)>;

// Parses the arguments after the program name. Reads the key and token files it is given, and
// UAVSIM_MAVLINK_KEY through env when no key option is given. Thread-safe (pure but for those files).
ParseResult parse_args(const std::vector<std::string>& args, const EnvLookup& env);

// Parses 64 hexadecimal digits (surrounding white space ignored) into a 32-byte signing key.
std::optional<std::array<uint8_t, 32>> parse_signing_key(const std::string& text);

// Why vehicle_count endpoints from base_port + 10 i do not fit under 65535 (nullopt when they do, or
// when base_port is 0 or -1). flag names the option in the message.
std::optional<std::string> port_range_error(const std::string& flag, int base_port, std::size_t vehicle_count);

// True for 127.0.0.0/8 and "localhost": addresses only this machine can reach.
bool is_loopback_address(const std::string& address);

const char* usage();
const char* version_string();

}  // namespace uavsim::server::app
