// Physics shards under the simulation (physics/world.hpp): each shard's vehicles, physics and
// flight controllers run on the thread that steps the shard, so the state after a flight is
// bit-identical for any number of threads.
#include <gtest/gtest.h>

#include <string>

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

TEST(ShardedSimulation, MoreThreadsThanShardsStartOnlyOnePerShard) {
  physics::ComposeOptions o;
  o.models_dir = UAVSIM_MODELS_DIR;
  const std::string path = grid_world(2, 2);
  EXPECT_EQ(physics::World::load(path, o, physics::ShardOptions{1, 2})->thread_count(), 1);
  EXPECT_EQ(physics::World::load(path, o, physics::ShardOptions{2, 8})->thread_count(), 2);
}

}  // namespace
}  // namespace uavsim::server::sim
