#include "app/server_app.hpp"

#include <atomic>
#include <fstream>
#include <iostream>
#include <limits>
#include <memory>
#include <thread>

#include "api/api_server.hpp"
#include "app/demo_flight.hpp"
#include "mavlink/endpoint.hpp"
#include "physics/world.hpp"
#include "sim/runner.hpp"
#include "sim/simulation.hpp"

namespace uavsim::server::app {

namespace {
std::atomic<bool> g_stop_requested{false};
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

  sim::Runner runner(s, options.rate);
  // the stop flag is polled at control steps (signal handlers may only set it)
  s.add_control_observer([&runner](sim::Simulation&) {
    if (g_stop_requested) runner.stop();
  });

  // the sim socket API: requests run in the control gate, on this (the loop) thread
  std::unique_ptr<api::ApiServer> api_server;
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
    runner.set_control_gate(api_server->gate());
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
    demo = std::make_unique<DemoFlight>(s, std::cout, options.quiet);
    s.add_control_observer([&runner, &demo](sim::Simulation&) {
      if (demo->finished()) runner.stop();
    });
  }

  const double end = options.duration_s > 0 ? options.duration_s : std::numeric_limits<double>::infinity();
  runner.run_until(end);
  if (api_server) api_server->shutdown();

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
