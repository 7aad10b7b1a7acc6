// The scale world (models/worlds/grid1000.xml): 1000 lean quads start parked on the ground; 100 of
// them take off and hover while the rest stay parked. Half a minute of wall time: labelled
// scenario.
#include <gtest/gtest.h>

#include "grid_flight.hpp"

namespace uavsim::server::sim {
namespace {

TEST(Scale, AThousandQuadsStartOnTheGroundAndAHundredOfThemTakeOff) {
  testing::fly_some_of_a_grid(std::string(UAVSIM_MODELS_DIR) + "/worlds/grid1000.xml", 1000, 100);
}

// Physics shards at scale (physics/world.hpp): 200 quads in 2 shards start on the ground, all take off
// (in two waves of 100, 0.5 s apart) and hover; the state after the flight is bit-identical whether one thread or two step the shards.
TEST(Scale, TwoHundredQuadsInTwoShardsTakeOffIdenticallyOnOneAndTwoThreads) {
  const std::string path = testing::grid_world(10, 20);
  const uint64_t one = testing::fly_all_of_a_sharded_grid(path, 200, 2, 1, 100, 12.0);
  const uint64_t two = testing::fly_all_of_a_sharded_grid(path, 200, 2, 2, 100, 12.0);
  EXPECT_EQ(one, two);
}

}  // namespace
}  // namespace uavsim::server::sim
