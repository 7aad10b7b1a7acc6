#include "app/server_app.hpp"

#include <algorithm>
#include <atomic>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <deque>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <limits>
#include <memory>
#include <optional>
#include <thread>

#include "api/api_server.hpp"
#include "api/overlay_ops.hpp"
#include "api/radio_ops.hpp"
#include "api/sensor_ops.hpp"
#include "app/camera_floor.hpp"
#include "app/camera_owners.hpp"
#include "app/demo_flight.hpp"
#include "app/endpoint_hooks.hpp"
#include "app/field_setup.hpp"
#include "app/gimbal_bridge.hpp"
#include "app/hover_all.hpp"
#include "app/loop_guard.hpp"
#include "app/param_file.hpp"
#include "app/recording.hpp"
#include "app/run_reporter.hpp"
#include "mavlink/endpoint.hpp"
#include "net/event_loop.hpp"
#include "objects/world_objects.hpp"
#include "physics/object_bodies.hpp"
#include "physics/world.hpp"
#include "radio/gcs_relay.hpp"
#include "render/camera_director.hpp"
#include "render/camera_setup.hpp"
#include "render/frame_service.hpp"
#include "render/plane_grid.hpp"
#include "render/video_recorder.hpp"
#include "sim/runner.hpp"
#include "sim/simulation.hpp"

namespace uavsim::server::app {

namespace {
std::atomic<bool> g_stop_requested{false};
std::atomic<int> g_stop_signal{0};  // the signal that asked to stop (0: none, or stop_server())
static_assert(std::atomic<int>::is_always_lock_free && std::atomic<bool>::is_always_lock_free,
              "set from a signal handler");

// a socket error with the option that avoids it: another process (often another uavsim-server) holds the port
std::string with_port_hint(const std::string& what, const char* flag) {
  if (what.find("in use") == std::string::npos) return what;
  return what + " (another server running? " + flag + " 0 picks free ports and prints them)";
}

const UdpOut kDefaultUdpOut{"udp:127.0.0.1:14550", 0};  // QGroundControl listens there

// vehicle i's UDP links from the --out options (the default: vehicle 0 to QGroundControl's 14550)
std::vector<std::vector<mavlink::UdpEndpoint>> udp_links(const Options& options, std::size_t vehicles) {
  std::vector<UdpOut> outs = options.udp_outs;
  // the default goes with a fixed TCP port (a run by hand): runs on ephemeral ports (tests, launchers,
  // sweeps) and runs without MAVLink do not send to a ground station that may be watching
  if (!options.udp_outs_explicit && options.mavlink_base_port > 0) outs.push_back(kDefaultUdpOut);
  std::vector<std::vector<mavlink::UdpEndpoint>> links(vehicles);
  for (std::size_t i = 0; i < vehicles; ++i) {
    for (const UdpOut& out : outs) {
      std::string why;
      const auto t = udp_target(out, static_cast<int>(i), &why);
      if (!why.empty()) throw std::invalid_argument(why);
      if (t) links[i].push_back({t->listen, t->host, t->port});
    }
  }
  return links;
}

}  // namespace

common::GeodeticOrigin world_home(const physics::World& world, const Options& options) {
  mavlink::GeodeticOrigin origin;
  if (options.home) {
    origin.lat_deg = options.home->lat_deg;
    origin.lon_deg = options.home->lon_deg;
    origin.alt_m = options.home->alt_m;
    return origin;
  }
  const std::vector<double> h = physics::custom_numeric(world, "uavsim:home");
  if (h.empty()) return origin;
  const bool ok = h.size() == 3 && std::isfinite(h[0]) && std::isfinite(h[1]) && std::isfinite(h[2]) &&
                  std::abs(h[0]) <= 90.0 && std::abs(h[1]) <= 180.0 && h[2] >= -500.0 && h[2] <= 10000.0;
  if (!ok) {
    throw physics::WorldError("custom numeric uavsim:home needs data=\"LAT LON ALT\" (degrees, degrees, metres above "
                              "sea level; latitude -90..90, longitude -180..180, altitude -500..10000)");
  }
  origin.lat_deg = h[0];
  origin.lon_deg = h[1];
  origin.alt_m = h[2];
  return origin;
}

namespace {

std::size_t mavlink_clients(const mavlink::MavlinkServer* server) {
  if (server == nullptr) return 0;
  std::size_t n = 0;
  for (std::size_t i = 0; i < server->vehicle_count(); ++i) n += server->client_count(i);
  return n;
}
}  // namespace

std::vector<std::string> shipped_worlds(const std::string& models_dir) {
  std::vector<std::string> names;
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(models_dir + "/worlds", ec)) {
    if (entry.path().extension() == ".xml") names.push_back(entry.path().stem().string());
  }
  std::sort(names.begin(), names.end());
  return names;
}

std::string world_summary(const std::string& world_path, std::size_t max_chars) {
  // the leading comment, read from at most the first 64 KiB (a header, not the world)
  std::ifstream in(world_path);
  std::string head(64 * 1024, '\0');
  in.read(head.data(), static_cast<std::streamsize>(head.size()));
  head.resize(static_cast<std::size_t>(in.gcount()));
  const std::size_t open = head.find("<!--");
  if (open == std::string::npos || head.find('<') < open) return "";
  const std::size_t close = head.find("-->", open);
  if (close == std::string::npos) return "";
  // white space collapsed, up to the end of the first sentence
  std::string text;
  for (std::size_t i = open + 4; i < close; ++i) {
    const char c = head[i];
    const bool space = std::isspace(static_cast<unsigned char>(c)) != 0;
    if (space && (text.empty() || text.back() == ' ')) continue;
    text += space ? ' ' : c;
    if (c == '.' && i + 1 < close && std::isspace(static_cast<unsigned char>(head[i + 1])) != 0)
      break;
  }
  while (!text.empty() && (text.back() == ' ' || text.back() == '.')) text.pop_back();
  if (text.size() <= max_chars) return text;
  // cut at the last word that fits with the ellipsis
  std::size_t cut = text.rfind(' ', max_chars > 3 ? max_chars - 3 : 0);
  if (cut == std::string::npos || cut == 0) cut = max_chars > 3 ? max_chars - 3 : 0;
  text.resize(cut);
  while (!text.empty() && (text.back() == ',' || text.back() == ':' || text.back() == ' '))
    text.pop_back();
  return text + "...";
}

std::string list_worlds_text(const std::string& models_dir, const std::string& from) {
  std::string out = "# models: " + models_dir + " (" + from + ")\n";
  const std::vector<std::string> names = shipped_worlds(models_dir);
  std::size_t width = 0;
  for (const std::string& n : names) width = std::max(width, n.size());
  for (const std::string& n : names) {
    out += n + std::string(width - n.size() + 2, ' ') +
           world_summary(models_dir + "/worlds/" + n + ".xml") + "\n";
  }
  if (names.empty()) out += "# no worlds in " + models_dir + "/worlds\n";
  return out;
}

std::string resolve_world_path(const std::string& given, const std::string& models_dir) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (fs::is_regular_file(given, ec)) return given;
  // a shipped world by name ("mbzirc2020" or "mbzirc2020.xml")
  const fs::path by_name = fs::path(models_dir) / "worlds" / fs::path(given).filename();
  for (const fs::path& p : {by_name, fs::path(by_name.string() + ".xml")}) {
    if (fs::path(given).parent_path().empty() && fs::is_regular_file(p, ec)) return p.string();
  }
  std::string list;
  for (const std::string& n : shipped_worlds(models_dir)) list += (list.empty() ? "" : ", ") + n;
  throw std::runtime_error("no world file '" + given + "'; the shipped worlds are: " +
                           (list.empty() ? "(none found in " + models_dir + "/worlds)" : list) +
                           " (by name, or models/worlds/NAME.xml)");
}

std::vector<std::string> option_warnings(const Options& options) {
  std::vector<std::string> w;
  if (options.mavlink_base_port >= 0 && !is_loopback_address(options.bind_address)) {
    w.push_back("--bind " + options.bind_address +
                ": the MAVLink endpoints are reachable from other machines, and whoever reaches them can arm and "
                "fly the vehicles" +
                (options.mavlink_key ? "" : " (sign the links with --mavlink-key-file)"));
  }
  if (options.api_port >= 0 && !is_loopback_address(options.api_bind_address)) {
    w.push_back("--api-bind " + options.api_bind_address +
                ": the sim API is reachable from other machines, and whoever reaches it can pause, reset and "
                "kill" +
                (options.api_token ? " (clients must send the --api-token-file token)"
                                   : "; it has no authentication unless --api-token-file is given"));
  }
  return w;
}

void stop_server() { g_stop_requested = true; }

namespace {

// Whether anything can ask for a camera frame in this run: a sim API client (cameras are on unless
// --no-cameras), --record or --render-cameras. If not, no renderer is made and the world's vehicles
// need no visual-only geoms.
bool may_render(const Options& options) {
  return options.cameras &&
         (options.api_port >= 0 || options.record_path || !options.render_cameras.empty());
}

}  // namespace

void stop_server(int signal) {
  g_stop_signal = signal;
  g_stop_requested = true;
}

int run_server(const Options& given_options) {
  Options options = given_options;
  physics::ComposeOptions compose;
  const common::ModelsDir models = physics::find_models_dir(options.models_dir);
  compose.models_dir = models.path;
  if (options.list_worlds) {
    std::cout << list_worlds_text(models.path, common::to_string(models.from)) << std::flush;
    return shipped_worlds(models.path).empty() ? 1 : 0;
  }
  try {
    options.world_path = resolve_world_path(options.world_path, compose.models_dir);
  } catch (const std::exception& e) {
    std::cerr << "uavsim-server: " << e.what() << "\n";
    return 1;
  }
  for (const std::string& w : option_warnings(options)) std::cerr << "uavsim-server: warning: " << w << "\n";

  // --write-world: compose, write, done
  if (options.write_world_path) {
    try {
      const std::string mjcf = physics::compose_world(options.world_path, compose);
      std::ofstream out(*options.write_world_path);
      out << mjcf;
      if (!out) {
        std::cerr << "uavsim-server: cannot write " << *options.write_world_path << "\n";
        return 1;
      }
      std::cout << "wrote " << *options.write_world_path << "\n";
      return 0;
    } catch (const physics::WorldError& e) {
      std::cerr << "uavsim-server: " << e.what() << "\n";
      return 1;
    }
  }

  std::unique_ptr<sim::Simulation> simulation;
  mavlink::GeodeticOrigin origin;
  try {
    sim::SimConfig config;
    config.physics_hz = options.physics_hz;
    config.control_hz = options.control_hz;
    config.seed = options.seed;
    // a world nothing can render (no camera client, no recording) carries only the geoms that
    // collide
    compose.vehicle_visual_geoms = may_render(options);
    std::unique_ptr<physics::World> world = physics::World::load(
        options.world_path, compose, physics::ShardOptions{options.physics_shards, options.physics_threads});
    // parameters: the world's uavsim:params texts, then --defaults files
    std::vector<std::string> names;
    for (const physics::VehicleBinding& v : world->vehicles()) names.push_back(v.name);
    config.vehicle_params = vehicle_params(names, physics::custom_texts(*world, "uavsim:params:"), options.defaults_files);
    // field conditions: --realism / uavsim:realism, the world's settings, --wind; the field cameras' settings
    // go before the --camera overrides
    config.field = resolve_field_conditions(options, *world);
    if (!config.field.camera_settings.empty()) {
      options.camera_overrides.insert(options.camera_overrides.begin(), "*:" + config.field.camera_settings);
    }
    origin = world_home(*world, options);
    simulation = std::make_unique<sim::Simulation>(std::move(world), config);
  } catch (const std::exception& e) {
    std::cerr << "uavsim-server: " << e.what() << "\n";
    return 1;
  }
  sim::Simulation& s = *simulation;
  if (options.mavlink_base_port >= 0) {
    if (auto why = port_range_error("--mavlink-port", options.mavlink_base_port, s.vehicle_count())) {
      std::cerr << "uavsim-server: " << *why << "\n";
      return 2;
    }
  }

  // what the server says: event lines (unless --quiet) and --log-dir's events.jsonl
  common::RecordFile event_log;
  if (options.log_dir) {
    std::error_code ec;
    std::filesystem::create_directories(*options.log_dir, ec);
    if (std::string why; !event_log.open(*options.log_dir + "/events.jsonl", &why)) {
      std::cerr << "uavsim-server: --log-dir: " << why << "\n";
      return 1;
    }
  }
  RunReporter reporter(s, options.quiet ? nullptr : &std::cout, options.log_dir ? &event_log : nullptr, &std::cerr);
  if (options.log_dir && !options.quiet) {
    std::cout << "uavsim-server: logging to " << *options.log_dir << " (VEHICLE.tlog, events.jsonl)\n";
  }
  // world objects (truck, balloons, gimbals) found in the world
  objects::ObjectSet world_objects;
  try {
    world_objects = objects::create_world_objects(s);
  } catch (const std::exception& e) {
    std::cerr << "uavsim-server: " << options.world_path << ": " << e.what() << "\n";
    return 1;
  }
  if (!options.quiet) {
    std::cout << "uavsim-server: " << options.world_path << ": " << s.vehicle_count() << " vehicle(s), physics "
              << options.physics_hz << " Hz"
              << (s.world().shard_count() > 1 ? " in " + std::to_string(s.world().shard_count()) + " shards on " +
                                                     std::to_string(s.world().thread_count()) + " thread(s)"
                                               : std::string())
              << ", control " << 1.0 / s.control_dt_s() << " Hz, seed " << options.seed
              << ", clock " << (options.rate > 0 ? std::to_string(options.rate) + "x real time" : "as fast as possible")
              << "\n";
    const sim::FieldConditions& field = s.config().field;
    if (field.realism == sim::Realism::kField || s.wind().active()) {
      const airframe::WindParams& w = s.wind().params();
      std::cout << "uavsim-server: realism " << sim::realism_name(field.realism) << ", wind " << w.speed_m_s
                << " m/s from " << std::lround(w.from_deg) << " deg, turbulence " << w.turbulence_sd_m_s << " m/s\n";
    }
  }

  // one network I/O thread for the MAVLink endpoints and the sim API (docs/architecture.md, "Network
  // I/O"); declared first, so it outlives both servers
  net::EventLoop io_loop;
  io_loop.start();

  // MAVLink endpoints: vehicle i on base + 10 i
  std::unique_ptr<mavlink::MavlinkServer> mavlink_server;
  mavlink::EndpointConfig endpoint;
  try {
    endpoint.udp = udp_links(options, s.vehicle_count());
  } catch (const std::exception& e) {
    std::cerr << "uavsim-server: " << e.what() << "\n";
    return 2;
  }
  const bool any_udp = std::any_of(endpoint.udp.begin(), endpoint.udp.end(), [](const auto& v) { return !v.empty(); });
  if ((options.mavlink_base_port >= 0 || any_udp) && s.vehicle_count() > 0) {
    endpoint.base_port = options.mavlink_base_port;
    endpoint.bind_address = options.bind_address;
    endpoint.signing_key = options.mavlink_key;
    endpoint.origin = origin;
    if (options.log_dir) endpoint.tlog_dir = *options.log_dir;
    endpoint.on_client = [&reporter](std::size_t v, bool connected, const std::string& peer) {
      reporter.on_client(v, connected, peer);
    };
    endpoint.on_status_text = [&reporter](std::size_t v, int severity, const std::string& text) {
      reporter.on_status_text(v, severity, text);
    };
    // the gimbal devices report their cameras' measured attitude
    if (const objects::GimbalSet* gimbals = world_objects.gimbals) {
      endpoint.gimbal_attitude = [gimbals, &s](std::size_t v) {
        return gimbal_device_attitude(*gimbals, s, v);
      };
    }
    try {
      mavlink_server = std::make_unique<mavlink::MavlinkServer>(s, endpoint, &io_loop);
    } catch (const std::exception& e) {
      std::cerr << "uavsim-server: " << with_port_hint(e.what(), "--mavlink-port") << "\n";
      return 1;
    }
    if (!options.quiet) {
      for (size_t i = 0; i < s.vehicle_count(); ++i) {
        std::cout << "uavsim-server: " << s.vehicle_name(i) << ": MAVLink on";
        if (options.mavlink_base_port >= 0) {
          std::cout << " tcp:" << endpoint.bind_address << ":" << mavlink_server->port(i);
        }
        for (std::size_t k = 0; k < endpoint.udp[i].size(); ++k) {
          const mavlink::UdpEndpoint& u = endpoint.udp[i][k];
          std::cout << (u.listen ? " udpin:" : " udp:") << u.host << ":" << u.port;
          if (!u.listen) std::cout << " (from port " << mavlink_server->udp_port(i, k) << ")";
        }
        std::cout << "\n";
      }
      std::cout.flush();
    }
  }

  // MAVLink gimbal commands point the vehicles' camera gimbals
  std::unique_ptr<MavlinkGimbalBridge> gimbal_bridge;
  if (mavlink_server && world_objects.gimbals != nullptr) {
    mavlink::MavlinkServer* ms = mavlink_server.get();
    gimbal_bridge = std::make_unique<MavlinkGimbalBridge>(
        *world_objects.gimbals, [ms](size_t vehicle) -> const mavlink::GimbalState& { return ms->gimbal(vehicle); });
  }

  // the launchers' counters and notes for the video's overlay (overlay_* ops)
  api::OverlayOps overlay_ops(s);

  // cameras: the frame service (render thread) for the API's subscriptions, --record and
  // --render-cameras (whose consumer outlives the service that delivers to it)
  std::unique_ptr<CameraFloor> camera_floor;
  std::unique_ptr<render::FrameService> frames;
  std::unique_ptr<render::VideoRecorder> recorder;
  size_t recorded = 0;  // the camera --record films
  if (may_render(options)) {
    std::vector<render::CameraSetup> cameras;
    // which cameras and geoms are a vehicle's
    const render::CameraOwners owners = camera_owners(s.world(), world_objects);
    try {
      std::vector<std::string> overrides = options.camera_overrides;
      cameras = render::discover_cameras(s.world().model(), owners, overrides, 1.0 / s.control_dt_s());
      if (!cameras.empty() && s.world().shard_count() > 1) {
        throw std::invalid_argument("the world is split into " + std::to_string(s.world().shard_count()) +
                                    " physics shards, and a camera would see only the first shard's vehicles: "
                                    "use --no-cameras, or --physics-shards 1");
      }
      const auto probe = record_camera(cameras, options.record_camera);
      if (options.record_path) {
        if (!probe) throw std::invalid_argument("--record-camera " + options.record_camera + ": no such camera");
        recorded = *probe;
      }
      if (options.record_path) {
        // the recorded camera takes the recording's size and rate
        render::CameraConfig& c = cameras[*probe].config;
        c.width_px = options.record_width;
        c.height_px = options.record_height;
        c.fps_hz = options.record_fps;
        if (c.fps_hz > 1.0 / s.control_dt_s()) throw std::invalid_argument("--record-fps is above the control rate");
      }
    } catch (const std::exception& e) {
      std::cerr << "uavsim-server: " << options.world_path << ": " << e.what() << "\n";
      return 1;
    }
    if (!cameras.empty()) {
      try {
        render::FrameServiceOptions frame_options;
        frame_options.seed = options.seed;
        frame_options.backend = options.gl_backend;
        frame_options.render_threads = options.render_threads;
        frame_options.owners = owners;
        frames = std::make_unique<render::FrameService>(s.world().model(), cameras, frame_options);
        if (!options.quiet) {
          std::cout << "uavsim-server: " << cameras.size() << " camera(s) rendered by " << frames->render_threads()
                    << " thread(s) with " << frames->gl_summary() << "\n";
        }
        for (const std::string& w : render::dense_plane_grid_warnings(s.world().model())) {
          std::cerr << "uavsim-server: warning: " << w << "\n";
        }
      } catch (const std::exception& e) {
        if (options.record_path || !options.render_cameras.empty()) {
          std::cerr << "uavsim-server: " << (options.record_path ? "--record" : "--render-cameras")
                    << ": " << e.what() << "\n";
          return 1;
        }
        std::cerr << "uavsim-server: warning: no camera frames: " << e.what() << "\n";
      }
    }
    if (frames && options.record_path) {
      const std::optional<size_t> cam = recorded;
      try {
        // as fast as possible (--rate 0) nothing is lost by waiting for the video; at a real-time rate it never waits
        render::RecorderOptions ro;
        ro.lossless = options.rate == 0.0;
        for (const std::string& t : options.record_tiles) {
          // --record-tile CAMERA[:MODALITY] (the modality checked by the options)
          const size_t colon = t.find(':');
          const std::optional<int> tile = frames->find(t.substr(0, colon));
          if (!tile) throw std::invalid_argument("--record-tile " + t + ": no such camera");
          ro.tiles.push_back(*tile);
          ro.tile_modalities.push_back(
              render::encoding_from_name(colon == std::string::npos ? "rgb" : t.substr(colon + 1)).value());
        }
        if (options.record_tiled && options.record_tiles.empty()) {
          // the vehicles' onboard cameras, the first kMaxTiles of the world's order
          constexpr size_t kMaxTiles = 4;
          for (size_t i = 0; i < frames->cameras().size() && ro.tiles.size() < kMaxTiles; ++i) {
            if (frames->cameras()[i].vehicle >= 0 && i != *cam) ro.tiles.push_back(static_cast<int>(i));
          }
        }
        // said once, like a tlog the disk refuses; the mission launchers end the run on it
        ro.on_write_error = [](const std::string& why) {
          std::fprintf(stderr, "uavsim-server: the video stops here: %s\n", why.c_str());
        };
        recorder = std::make_unique<render::VideoRecorder>(*frames, static_cast<int>(*cam), *options.record_path,
                                                           std::move(ro));
      } catch (const std::exception& e) {
        std::cerr << "uavsim-server: " << e.what() << "\n";
        return 1;
      }
      frames->add_consumer(recorder.get());
      // follow / top: the filmed camera is posed from the vehicles; the overlay labels them
      std::vector<int> bodies;
      for (const physics::VehicleBinding& v : s.world().vehicles()) bodies.push_back(v.body_id);
      frames->set_tracked_bodies(bodies);
      try {
        if (auto director = record_director(options.record_camera, frames->cameras()[*cam], s)) {
          frames->set_director(static_cast<int>(*cam), std::move(director));
        }
      } catch (const std::exception& e) {
        std::cerr << "uavsim-server: " << e.what() << "\n";
        return 2;
      }
      if (options.record_overlay) recorder->set_overlay(record_overlay_source(s, world_objects, reporter, overlay_ops));
      if (!options.quiet) {
        std::cout << "uavsim-server: recording camera " << cameras[*cam].config.camera << " to " << *options.record_path
                  << " as " << options.record_camera << ", " << recorder->width_px() << "x" << recorder->height_px()
                  << (options.record_tiled ? " tiled" : "") << " (" << recorder->encoder() << ")\n";
      }
    }
    if (!options.render_cameras.empty()) {
      // the names and rates are checked now that the cameras are known (none: frames is null)
      try {
        camera_floor = std::make_unique<CameraFloor>(
            frames ? frames->cameras() : std::vector<render::FrameCamera>{},
            options.render_cameras);
      } catch (const std::exception& e) {
        std::cerr << "uavsim-server: " << e.what() << "\n";
        return 2;
      }
      frames->add_consumer(camera_floor.get());
    }
  }

  sim::Runner runner(s, options.rate);

  // the sim socket API: requests run in the control gate, on this (the loop) thread
  radio::SimRadio* radio = nullptr;  // owned by s
  bool radio_failed = false;          // a radio's channel (A2A or GCS link) failed: the run ended early
  radio::GcsRelaySet* gcs_relays = nullptr;  // likewise
  std::unique_ptr<api::RadioOps> radio_ops;  // outlives api_server, which serves its ops
  std::unique_ptr<api::SensorOps> sensor_ops;  // likewise
  std::unique_ptr<api::ApiServer> api_server;
  std::unique_ptr<EndpointHooks> endpoint_hooks;
  if (options.api_port >= 0) {
    api::ApiConfig api_config;
    api_config.port = static_cast<uint16_t>(options.api_port);
    api_config.bind_address = options.api_bind_address;
    api_config.lockstep_timeout_s = options.lockstep_timeout_s;
    api_config.token = options.api_token;
    api_config.io_loop = &io_loop;
    try {
      api_server = std::make_unique<api::ApiServer>(s, &runner, world_objects, api_config);
    } catch (const std::exception& e) {
      std::cerr << "uavsim-server: " << with_port_hint(e.what(), "--api-port") << "\n";
      return 1;
    }
    api_server->set_stop_check([] { return g_stop_requested.load(); });
    if (mavlink_server) {
      endpoint_hooks = std::make_unique<EndpointHooks>(*mavlink_server);
      api_server->set_link_control(endpoint_hooks.get());
      api_server->set_seq_waiter(endpoint_hooks.get());
    }
    if (frames) api_server->set_frame_service(frames.get());
    // the A2A radio and the GCS link relay (seed 6.2, 6.3), served as radio_* / gcs_link_* ops
    radio::BackendOptions backend;
    radio::RadioConfig radio_config;
    try {
      // the channel: --radio-backend, else the world's uavsim:radio_backend; the world's obstacle losses
      if (options.radio_backend) backend.backend = *radio::backend_from_name(*options.radio_backend);
      radio::apply_world_radio_settings(s.world(), &backend, options.radio_backend.has_value(), &radio_config);
      radio = &radio::SimRadio::create(s, radio_config, backend);
    } catch (const std::exception& e) {
      std::cerr << "uavsim-server: radio: " << e.what() << "\n";
      return 1;
    }
    // a radio that fails (the ns3 helper died or hung) ends the run: never a silently perfect radio
    const auto end_run_on_failure = [&runner, &radio_failed](const std::string& what) {
      return [&runner, &radio_failed, what](const std::string& why) {
        std::cerr << "uavsim-server: " << what << ": " << why << "; ending the run\n";
        radio_failed = true;
        runner.stop();
      };
    };
    radio->set_on_failure(end_run_on_failure("radio"));
    if (!options.quiet) {
      std::cout << "uavsim-server: radio: " << radio->model().backend_name() << " backend, frames of at most "
                << radio->model().max_payload_bytes() << " bytes" << "\n";
    }
    gcs_relays = &radio::GcsRelaySet::create(s, options.api_bind_address);
    // the GCS link's channel: --gcs-link-backend, else the world's uavsim:gcs_link_backend; ns3
    // carries its datagrams over 802.11 between each vehicle and a ground node
    try {
      bool gcs_ns3 = options.gcs_link_backend == "ns3";
      radio::GcsRadioOptions gcs_radio;
      if (options.gcs_position) {
        gcs_radio.gcs_position_enu_m =
            Eigen::Vector3d((*options.gcs_position)[0], (*options.gcs_position)[1], (*options.gcs_position)[2]);
      }
      radio::apply_world_gcs_settings(s.world(), options.gcs_link_backend.has_value(), &gcs_ns3, &gcs_radio);
      if (gcs_ns3) gcs_relays->use_radio(std::make_unique<radio::GcsRadioLink>(s, gcs_radio));
    } catch (const std::exception& e) {
      std::cerr << "uavsim-server: gcs link: " << e.what() << "\n";
      return 1;
    }
    gcs_relays->set_on_failure(end_run_on_failure("gcs link radio"));
    if (!options.quiet && gcs_relays->radio() != nullptr) {
      const Eigen::Vector3d& g = gcs_relays->radio()->gcs_position_enu_m();
      std::cout << "uavsim-server: gcs link: ns3 backend (802.11g ad hoc, 6 Mbit/s), ground station at (" << g.x()
                << ", " << g.y() << ", " << g.z() << ") m, datagrams of at most "
                << gcs_relays->radio()->max_datagram_bytes() << " bytes\n";
    }
    api::GcsTargetPolicy gcs_targets{options.allow_remote_gcs,
                                     [api = api_server.get()](uint64_t conn) { return api->peer_address(conn); }};
    radio_ops = std::make_unique<api::RadioOps>(s, *radio, gcs_relays, std::move(gcs_targets));
    radio_ops->set_shm_transport(&api_server->shm_transport());
    api_server->add_group(radio_ops.get());
    // onboard sensors: the landing-pad microswitches (sensor_* ops)
    sensor_ops = std::make_unique<api::SensorOps>(s);
    api_server->add_group(sensor_ops.get());
    api_server->add_group(&overlay_ops);
    api_server->start();
    if (!options.quiet) {
      std::cout << "uavsim-server: sim API on tcp:" << api_config.bind_address << ":" << api_server->port()
                << "\n";
      std::cout.flush();
    }
  }

  std::unique_ptr<DemoFlight> demo;
  if (options.demo) {
    if (s.vehicle_count() == 0) {
      std::cerr << "uavsim-server: --demo needs a world with a vehicle\n";
      return 1;
    }
    demo = std::make_unique<DemoFlight>(std::cout, options.quiet);
  }

  std::unique_ptr<HoverAll> hover;
  if (options.hover_m) {
    hover = std::make_unique<HoverAll>(*options.hover_m, std::cout, options.quiet);
    if (!options.quiet) {
      std::cout << "uavsim-server: --hover: every vehicle takes off to " << *options.hover_m
                << " m and holds\n";
    }
  }

  // the step schedule (sim/step_schedule.hpp, docs/architecture.md): each component's place in a step,
  // registered here once; inside a phase they run in the order written here, the simulation's own work
  // (sim.*) before or after them as the schedule declares
  sim::StepSchedule& steps = s.schedule();
  // capture, queued tasks: gates, whose wall time holds the clock (Runner::add_gate); camera snapshots
  // due now first, of the state the last step left, then the sim API (requests, pause, lockstep), then
  // the vehicles' queued tasks (sim.vehicle_tasks)
  if (frames) {
    render::FrameService* fs = frames.get();
    runner.add_gate(sim::Phase::kCapture, "frames", [fs, &s](double) { fs->capture(s.world().data()); });
  }
  if (api_server) runner.add_gate(sim::Phase::kQueuedTasks, "api", api_server->gate());
  // post-control: what reads the control step's result (events out, telemetry, gimbal commands), the
  // stop flag (signal handlers may only set it), the demo, the GCS link relays' datagrams
  steps.add(sim::Phase::kPostControl, "reporter", [&reporter] { reporter.on_control_step(); });
  if (mavlink_server) mavlink_server->schedule(steps);
  if (gimbal_bridge) {
    steps.add(sim::Phase::kPostControl, "gimbal_bridge", [&gimbal_bridge, &s] { gimbal_bridge->update(s); });
  }
  steps.add(sim::Phase::kPostControl, "stop_signal", [&runner] {
    if (g_stop_requested) runner.stop();
  });
  if (hover)
    steps.add(sim::Phase::kPostControl, "hover", [&hover, &s] { hover->on_control_step(s); });
  if (demo) {
    steps.add(sim::Phase::kPostControl, "demo", [&runner, &demo, &s] {
      demo->on_control_step(s);
      if (demo->finished()) runner.stop();
    });
  }
  // pre-physics (after the wind, before the rotor forces), contact handlers, reset hooks: the world
  // objects (trucks, balloons, gimbals), then the radio; the relays (post-control) reset last
  objects::schedule_world_objects(s, world_objects);
  if (radio != nullptr) radio->schedule(steps);
  if (gcs_relays != nullptr) gcs_relays->schedule(steps);
  if (options.print_schedule) std::cout << "uavsim-server: step schedule\n" << steps.describe() << std::flush;

  // --wait-for-clients: the clock starts when enough MAVLink and sim API clients are connected (the API's
  // requests are answered from then on), so --rate 0 does not race through an empty world
  if (options.wait_for_clients > 0) {
    if (!options.quiet) {
      std::cout << "uavsim-server: waiting for " << options.wait_for_clients << " client(s) before starting the clock"
                << std::endl;
    }
    const auto clients = [&] {
      return mavlink_clients(mavlink_server.get()) + (api_server ? api_server->connection_count() : 0);
    };
    while (!g_stop_requested && clients() < static_cast<std::size_t>(options.wait_for_clients)) {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  }

  const double end = options.duration_s > 0 ? options.duration_s : std::numeric_limits<double>::infinity();
  // the watchdog: a loop stuck in one place is reported, and one that ignores a stop signal is left
  sim::WatchdogOptions watch;
  if (options.watchdog_s > 0) watch.stall_s = options.watchdog_s;
  std::optional<LoopGuard> guard;
  guard.emplace(s.schedule().activity(), watch, options.watchdog_s > 0, [] { return g_stop_signal.load(); },
                std::cerr, [](int code) { std::_Exit(code); });
  runner.run_until(end);
  guard->loop_finished();
  if (api_server) api_server->shutdown();
  if (frames) {
    // the last frames, then the renderer stops before its consumers go
    frames->wait_delivered();
    const render::FrameServiceStats fstats = frames->stats();
    frames.reset();
    if (recorder) {
      recorder->finish();
      const render::RecorderStats r = recorder->stats();
      std::cout << "uavsim-server: recorded " << r.frames_written << " frames to " << *options.record_path << ", "
                << r.frames_dropped << " dropped (" << fstats.frames_rendered << " frames rendered in all)\n";
    }
  }

  reporter.on_control_step();  // events of the last step
  if (const std::string stalls = guard->summary(); stalls != "no stalls") {
    std::cerr << "uavsim-server: watchdog: " << stalls << " of the simulation loop in this run\n";
  }
  if (radio_failed) return 1;
  if (!options.quiet) {
    std::string extra;
    if (mavlink_server) {
      std::uint64_t sent = 0, received = 0;
      for (std::size_t i = 0; i < mavlink_server->vehicle_count(); ++i) {
        const mavlink::EndpointStats st = mavlink_server->stats(i);
        sent += st.frames_sent;
        received += st.frames_received;
      }
      extra = "MAVLink frames: " + std::to_string(sent) + " sent, " + std::to_string(received) + " received";
    }
    if (camera_floor) {
      if (!extra.empty()) extra += "; ";
      extra += camera_floor->summary();
    }
    if (api_server && api_server->shm_transport().activated_total() > 0) {
      if (!extra.empty()) extra += "; ";
      extra += "sim API connections on shared memory: " +
               std::to_string(api_server->shm_transport().activated_total());
    }
    reporter.print_summary(std::cout, extra);
  }
  if (demo) {
    demo->print_summary(std::cout);
    return demo->result().success ? 0 : 3;
  }
  return 0;
}

}  // namespace uavsim::server::app
