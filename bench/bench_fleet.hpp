// Fleets for the benches: N lean quads on a 4 m grid in a world file of their own, loaded (optionally in
// physics shards), and launched from the ground into a hovering formation. Header-only: each
// <area>_bench.cpp is one binary.
#pragma once

#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include <mujoco/mujoco.h>

#include "fc/flight_controller.hpp"
#include "physics/world.hpp"
#include "sim/simulation.hpp"

namespace uavsim::bench {

using namespace uavsim::server;

inline std::string grid_world(int n, double z_m, const char* collision) {
  // the most square grid of exactly n: rows = the largest divisor of n not above sqrt(n)
  int rows = 1;
  for (int r = 1; r * r <= n; ++r) {
    if (n % r == 0) rows = r;
  }
  const int cols = n / rows;
  const std::string path = (std::filesystem::temp_directory_path() /
                            ("uavsim_bench_grid" + std::to_string(n) + collision + ".xml"))
                               .string();
  std::ofstream(path) << "<mujoco><compiler angle=\"radian\"/><option timestep=\"0.001\"/>"
                      << "<worldbody><geom name=\"ground\" type=\"plane\" size=\"500 500 0.1\"/>"
                      << "<uavsim_grid type=\"quad\" prefix=\"uav\" rows=\"" << rows << "\" cols=\""
                      << cols << "\" spacing=\"4\" pos=\"0 0 " << z_m << "\" collision=\""
                      << collision << "\"/></worldbody></mujoco>";
  return path;
}

inline std::unique_ptr<physics::World> load(int n, double z_m, const char* collision,
                                     physics::ShardOptions shards = {}) {
  physics::ComposeOptions o;
  o.models_dir = UAVSIM_MODELS_DIR;
  return physics::World::load(grid_world(n, z_m, collision), o, shards);
}

// launch every vehicle (GUIDED, arm, take off to 5 m), in each shard as many at a time as its constraint
// rows hold (16 per quad awake on its gear, world_composer.cpp auto_njmax), then hover for hover_s
inline void launch_all_sharded(sim::Simulation& s, int rows_per_shard, double hover_s) {
  const auto& vehicles = s.world().vehicles();
  const size_t shards = static_cast<size_t>(s.world().shard_count());
  std::vector<std::vector<size_t>> block(shards);
  for (size_t i = 0; i < vehicles.size(); ++i) block[static_cast<size_t>(vehicles[i].shard)].push_back(i);
  std::vector<size_t> next(shards, 0);
  const double give_up_s = s.time_s() + 20.0 + 0.05 * static_cast<double>(vehicles.size());
  auto done = [&] {
    for (size_t k = 0; k < shards; ++k) {
      if (next[k] < block[k].size()) return false;
    }
    return true;
  };
  while (!done() && s.time_s() < give_up_s) {
    for (size_t k = 0; k < shards; ++k) {
      size_t grounded_awake = 0;
      for (size_t j = 0; j < next[k]; ++j) {
        const size_t i = block[k][j];
        grounded_awake += s.truth(i).on_ground && !s.world().parked(i);
      }
      while (next[k] < block[k].size() && static_cast<int>(16 * (grounded_awake + 1)) <= rows_per_shard - 500) {
        s.post(block[k][next[k]++], [](fc::FlightController& f) {
          f.set_mode(fc::Mode::kGuided);
          f.arm(false);
          f.takeoff(5.0);
        });
        ++grounded_awake;
      }
    }
    s.run_until(s.time_s() + 0.1);
  }
  s.run_until(s.time_s() + hover_s);
}

// vehicles armed and not crashed
inline size_t flying(const sim::Simulation& s) {
  size_t n = 0;
  for (size_t i = 0; i < s.vehicle_count(); ++i) n += s.fc(i).armed() && !s.runtime(i).crashed;
  return n;
}

// an unsharded world: as many at a time as its constraint rows hold, then hover 10 s
inline void launch_all(sim::Simulation& s) { launch_all_sharded(s, s.world().model()->njmax, 10.0); }

}  // namespace uavsim::bench
