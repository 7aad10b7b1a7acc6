// Physics shards under the simulation (physics/world.hpp): each shard's vehicles, physics and
// flight controllers run on the thread that steps the shard, so the state after a flight (physics,
// autopilots, motors, batteries, events) is bit-identical for any number of threads.
#include <gtest/gtest.h>

#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "grid_flight.hpp"

namespace uavsim::server::sim {
namespace {

using testing::grid_world;

TEST(ShardedSimulation, TwentyQuadsTakeOffInTwoShardsIdenticallyOnOneAndTwoThreads) {
  const std::string path = grid_world(4, 5);
  // two waves of 10, then hover to t = 12 s
  const uint64_t one = testing::fly_all_of_a_sharded_grid(path, 20, 2, 1, 10, 12.0);
  const uint64_t two = testing::fly_all_of_a_sharded_grid(path, 20, 2, 2, 10, 12.0);
  EXPECT_EQ(one, two);
}

// Eight quads in two shards take off; then a NaN reaction-torque coefficient in one vehicle of each
// shard (its rotor wrench non-finite) and a runaway pose of a third: the non-finite-state rule, run
// on the shards' threads, faults the three, and the events come in the same order at the same times
// with the same state on 1 and 2 threads. Returns vehicles_hash().
uint64_t fault_in_both_shards(int threads) {
  physics::ComposeOptions o;
  o.models_dir = UAVSIM_MODELS_DIR;
  Simulation sim(physics::World::load(grid_world(2, 4), o, physics::ShardOptions{2, threads}), SimConfig{});
  EXPECT_EQ(sim.world().thread_count(), threads);
  testing::wait_ready(sim);
  for (size_t i = 0; i < sim.vehicle_count(); ++i) {
    sim.post(i, [](fc::FlightController& f) {
      f.set_mode(fc::Mode::kGuided);
      f.arm(false);
      f.takeoff(5.0);
    });
  }
  sim.run_until(sim.time_s() + 6.0);
  sim.world().mutable_airframe(1).rotors[0].torque_coef_m = std::numeric_limits<double>::quiet_NaN();
  sim.world().mutable_airframe(6).rotors[2].torque_coef_m = std::numeric_limits<double>::quiet_NaN();
  const double far[3] = {1e7, 0.0, 0.0};
  const double level[4] = {1.0, 0.0, 0.0, 0.0};
  sim.world().set_pose(4, far, level);
  sim.run_until(sim.time_s() + 2.0);
  std::vector<std::pair<int, std::string>> faults;
  for (const Event& e : sim.events().recent()) {
    if (e.type == EventType::kStateFault) faults.emplace_back(e.vehicle, e.detail);
  }
  // the wrenches are judged before mj_step, the runaway state after it: two events, then one
  EXPECT_EQ(faults, (std::vector<std::pair<int, std::string>>{{1, "non-finite or runaway rotor force"},
                                                              {6, "non-finite or runaway rotor force"},
                                                              {4, "non-finite or runaway state"}}));
  for (int i : {0, 2, 3, 5, 7}) EXPECT_TRUE(sim.fc(static_cast<size_t>(i)).armed()) << i;
  return testing::vehicles_hash(sim);
}

TEST(ShardedSimulation, FaultsOnTheShardThreadsGiveTheSameEventsAndStatesOnOneAndTwoThreads) {
  EXPECT_EQ(fault_in_both_shards(1), fault_in_both_shards(2));
}

TEST(ShardedSimulation, MoreThreadsThanShardsStartOnlyOnePerShard) {
  physics::ComposeOptions o;
  o.models_dir = UAVSIM_MODELS_DIR;
  const std::string path = grid_world(2, 2);
  EXPECT_EQ(physics::World::load(path, o, physics::ShardOptions{1, 2})->thread_count(), 1);
  EXPECT_EQ(physics::World::load(path, o, physics::ShardOptions{2, 8})->thread_count(), 2);
}

}  // namespace
}  // namespace uavsim::server::sim
