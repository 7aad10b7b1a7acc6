#include "app/server_app.hpp"

#include <atomic>
#include <fstream>
#include <iostream>
#include <limits>
#include <memory>
#include <thread>

#include "api/api_server.hpp"
#include "api/radio_ops.hpp"
#include "app/demo_flight.hpp"
#include "app/gimbal_bridge.hpp"
#include "mavlink/endpoint.hpp"
#include "physics/world.hpp"
#include "render/camera_setup.hpp"
#include "render/frame_service.hpp"
#include "render/video_recorder.hpp"
#include "sim/runner.hpp"
#include "app/endpoint_hooks.hpp"
#include "sim/simulation.hpp"

namespace uavsim::server::app {

namespace {
std::atomic<bool> g_stop_requested{false};

// which camera --record films: the world camera "overview", else the first world camera, else the first
std::optional<size_t> record_camera(const std::vector<render::CameraSetup>& cameras) {
  for (size_t i = 0; i < cameras.size(); ++i) {
    if (cameras[i].config.camera == "overview") return i;
  }
  for (size_t i = 0; i < cameras.size(); ++i) {
    if (cameras[i].vehicle < 0) return i;
  }
  if (!cameras.empty()) return 0;
  return std::nullopt;
}
}  // namespace

void stop_server() { g_stop_requested = true; }

int run_server(const Options& options) {
  physics::ComposeOptions compose;
  compose.models_dir = options.models_dir.empty() ? physics::default_models_dir() : options.models_dir;

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
  try {
    sim::SimConfig config;
    config.physics_hz = options.physics_hz;
    config.control_hz = options.control_hz;
    config.seed = options.seed;
    simulation = std::make_unique<sim::Simulation>(physics::World::load(options.world_path, compose), config);
  } catch (const std::exception& e) {
    std::cerr << "uavsim-server: " << e.what() << "\n";
    return 1;
  }
  sim::Simulation& s = *simulation;
  // world objects (truck, balloons, gimbals) found in the world
  objects::ObjectSet world_objects;
  try {
    world_objects = objects::add_world_objects(s);
  } catch (const std::exception& e) {
    std::cerr << "uavsim-server: " << options.world_path << ": " << e.what() << "\n";
    return 1;
  }
  if (!options.quiet) {
    std::cout << "uavsim-server: " << options.world_path << ": " << s.vehicle_count() << " vehicle(s), physics "
              << options.physics_hz << " Hz, control " << 1.0 / s.control_dt_s() << " Hz, seed " << options.seed
              << ", clock " << (options.rate > 0 ? std::to_string(options.rate) + "x real time" : "as fast as possible")
              << "\n";
  }

  // MAVLink endpoints: vehicle i on base + 10 i
  std::unique_ptr<mavlink::MavlinkServer> mavlink_server;
  if (options.mavlink_base_port >= 0 && s.vehicle_count() > 0) {
    mavlink::EndpointConfig endpoint;
    endpoint.base_port = options.mavlink_base_port;
    endpoint.bind_address = options.bind_address;
    endpoint.signing_key = options.mavlink_key;
    try {
      mavlink_server = std::make_unique<mavlink::MavlinkServer>(s, endpoint);
    } catch (const std::exception& e) {
      std::cerr << "uavsim-server: " << e.what() << "\n";
      return 1;
    }
    if (!options.quiet) {
      for (size_t i = 0; i < s.vehicle_count(); ++i) {
        std::cout << "uavsim-server: " << s.vehicle_name(i) << ": MAVLink on tcp:" << endpoint.bind_address << ":"
                  << mavlink_server->port(i) << "\n";
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
    s.add_control_observer([&gimbal_bridge](sim::Simulation& sim) { gimbal_bridge->update(sim); });
  }

  // cameras: the frame service (render thread) for the API's subscriptions and --record
  std::unique_ptr<render::FrameService> frames;
  std::unique_ptr<render::VideoRecorder> recorder;
  if (options.cameras && (options.api_port >= 0 || options.record_path)) {
    std::vector<render::CameraSetup> cameras;
    try {
      render::CameraOwners owners;
      for (const physics::VehicleBinding& v : s.world().vehicles()) owners.vehicle_root_bodies.emplace_back(v.body_id, v.name);
      if (world_objects.gimbals != nullptr) {
        for (const objects::Gimbal& g : world_objects.gimbals->gimbals()) owners.gimbal_body_vehicle[g.body_id] = g.vehicle;
      }
      std::vector<std::string> overrides = options.camera_overrides;
      const auto probe = record_camera(render::discover_cameras(s.world().model(), owners, overrides, 1.0 / s.control_dt_s()));
      if (options.record_path) {
        if (!probe) throw std::invalid_argument("--record: the world has no camera to film");
      }
      cameras = render::discover_cameras(s.world().model(), owners, overrides, 1.0 / s.control_dt_s());
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
        frames = std::make_unique<render::FrameService>(s.world().model(), cameras);
      } catch (const std::exception& e) {
        if (options.record_path) {
          std::cerr << "uavsim-server: --record: " << e.what() << "\n";
          return 1;
        }
        std::cerr << "uavsim-server: warning: no camera frames: " << e.what() << "\n";
      }
    }
    if (frames && world_objects.gimbals != nullptr) {
      // gimbal bodies at the vehicles' pose of the snapshot's instant, not the previous step's
      objects::GimbalSet* gimbals = world_objects.gimbals;
      frames->set_before_capture([gimbals, &s] { gimbals->before_step(s); });
    }
    if (frames && options.record_path) {
      const auto cam = record_camera(cameras);
      try {
        // as fast as possible (--rate 0) nothing is lost by waiting for the video; at a real-time rate it never waits
        recorder = std::make_unique<render::VideoRecorder>(*frames, static_cast<int>(*cam), 1, *options.record_path,
                                                           options.rate == 0.0);
      } catch (const std::exception& e) {
        std::cerr << "uavsim-server: " << e.what() << "\n";
        return 1;
      }
      frames->add_consumer(recorder.get());
      if (!options.quiet) {
        std::cout << "uavsim-server: recording camera " << cameras[*cam].config.camera << " to " << *options.record_path
                  << " (" << recorder->encoder() << ")\n";
      }
    }
  }

  sim::Runner runner(s, options.rate);
  // the stop flag is polled at control steps (signal handlers may only set it)
  s.add_control_observer([&runner](sim::Simulation&) {
    if (g_stop_requested) runner.stop();
  });

  // the sim socket API: requests run in the control gate, on this (the loop) thread
  std::unique_ptr<api::RadioOps> radio_ops;  // outlives api_server, which serves its ops
  std::unique_ptr<api::ApiServer> api_server;
  std::unique_ptr<EndpointHooks> endpoint_hooks;
  if (options.api_port >= 0) {
    api::ApiConfig api_config;
    api_config.port = static_cast<uint16_t>(options.api_port);
    api_config.bind_address = options.api_bind_address;
    api_config.lockstep_timeout_s = options.lockstep_timeout_s;
    try {
      api_server = std::make_unique<api::ApiServer>(s, &runner, world_objects, api_config);
    } catch (const std::exception& e) {
      std::cerr << "uavsim-server: " << e.what() << "\n";
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
    radio_ops = std::make_unique<api::RadioOps>(s, radio::SimRadio::attach(s, radio::RadioConfig{}),
                                                &radio::GcsRelaySet::attach(s, options.api_bind_address));
    api_server->add_extension(radio_ops.get());
    api_server->start();
    if (!options.quiet) {
      std::cout << "uavsim-server: sim API on tcp:" << api_config.bind_address << ":" << api_server->port()
                << "\n";
      std::cout.flush();
    }
  }

  // the gate before each control step: frames due now first, then the API (requests, pause, lockstep)
  if (frames || api_server) {
    sim::Runner::Gate api_gate = api_server ? api_server->gate() : sim::Runner::Gate{};
    render::FrameService* fs = frames.get();
    runner.set_control_gate([fs, api_gate, &s](double t) {
      if (fs != nullptr) fs->capture(s.world().data());
      if (api_gate) api_gate(t);
    });
  }

  std::unique_ptr<DemoFlight> demo;
  if (options.demo) {
    if (s.vehicle_count() == 0) {
      std::cerr << "uavsim-server: --demo needs a world with a vehicle\n";
      return 1;
    }
    demo = std::make_unique<DemoFlight>(s, std::cout, options.quiet);
    s.add_control_observer([&runner, &demo](sim::Simulation&) {
      if (demo->finished()) runner.stop();
    });
  }

  const double end = options.duration_s > 0 ? options.duration_s : std::numeric_limits<double>::infinity();
  runner.run_until(end);
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

  for (const sim::Event& e : s.events().all()) {
    if (e.type == sim::EventType::kCrash && !options.quiet) {
      std::cout << "event t=" << e.time_s << "s " << sim::event_type_name(e.type) << " "
                << s.vehicle_name(e.vehicle) << ": " << e.detail << "\n";
    }
  }
  if (demo) {
    demo->print_summary(std::cout);
    return demo->result().success ? 0 : 3;
  }
  return 0;
}

}  // namespace uavsim::server::app
