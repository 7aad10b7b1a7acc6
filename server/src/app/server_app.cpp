#include "app/server_app.hpp"

#include <atomic>
#include <fstream>
#include <iostream>
#include <limits>
#include <memory>
#include <thread>

#include "app/demo_flight.hpp"
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
  if (!options.quiet) {
    std::cout << "uavsim-server: " << options.world_path << ": " << s.vehicle_count() << " vehicle(s), physics "
              << options.physics_hz << " Hz, control " << 1.0 / s.control_dt_s() << " Hz, seed " << options.seed
              << ", clock " << (options.rate > 0 ? std::to_string(options.rate) + "x real time" : "as fast as possible")
              << "\n";
  }

  sim::Runner runner(s, options.rate);
  // the stop flag is polled at control steps (signal handlers may only set it)
  s.add_control_observer([&runner](sim::Simulation&) {
    if (g_stop_requested) runner.stop();
  });

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
