// Physics shards (physics/world.hpp): how the composer splits a world, which worlds it refuses, and
// the contact rule (vehicles in different shards pass through each other; all of them stand on the
// ground).
#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include <cmath>
#include <string>
#include <vector>

#include "physics/world.hpp"
#include "physics/world_composer.hpp"
#include "test_worlds.hpp"

namespace uavsim::server::physics {
namespace {

// a quad's body origin stands this high on its gear (models/vehicles/quad.xml)
constexpr double kGearHeight_m = 0.16;
constexpr double kRestTol_m = 0.02;

std::string write_world(const std::string& name, const std::string& worldbody) {
  return testing::write_world("uavsim_shard_test", name, worldbody);
}

ComposeOptions options() { return testing::source_models(); }

const std::string kGrid10 =
    R"(<uavsim_grid type="quad" prefix="uav" rows="2" cols="5" spacing="3" collision="lean"/>)";

TEST(PhysicsShards, SplitTheVehiclesInContiguousBlocksInWorldOrder) {
  const std::string path = write_world("grid10.xml", kGrid10);
  const auto whole = World::load(path, options());
  const auto sharded = World::load(path, options(), ShardOptions{3, 2});
  ASSERT_EQ(sharded->shard_count(), 3);
  EXPECT_EQ(sharded->thread_count(), 2);
  ASSERT_EQ(sharded->vehicles().size(), 10u);
  // blocks [k N / S, (k + 1) N / S): 0-2, 3-5, 6-9
  const int expected_shard[10] = {0, 0, 0, 1, 1, 1, 2, 2, 2, 2};
  for (size_t i = 0; i < 10; ++i) {
    EXPECT_EQ(sharded->vehicles()[i].name, whole->vehicles()[i].name);
    EXPECT_EQ(sharded->vehicles()[i].shard, expected_shard[i]) << i;
    EXPECT_EQ(sharded->vehicles()[i].airframe.mass_kg, whole->vehicles()[i].airframe.mass_kg);
    // every quad starts parked on the ground, in its own shard as in the whole world
    EXPECT_TRUE(sharded->parked(i));
    EXPECT_EQ(sharded->truth(i).position_enu_m, whole->truth(i).position_enu_m);
  }
  EXPECT_EQ(sharded->parked_count(), 10u);
  // shard 0 holds its 3 free bodies only, and the ground
  EXPECT_EQ(sharded->body_id("uav3"), -1);
  EXPECT_GE(sharded->body_id("uav2"), 0);
  EXPECT_EQ(sharded->model()->nv, 3 * 6);
  // and only the geoms that collide (it renders nothing): the ground and each lean quad's hull and two
  // skids, where the whole world keeps all 20 geoms of each quad for its cameras
  EXPECT_EQ(sharded->model()->ngeom, 1 + 3 * 3);
  EXPECT_EQ(whole->model()->ngeom, 1 + 10 * 20);
  EXPECT_EQ(sharded->vehicles()[0].airframe.inertia_body_kgm2, whole->vehicles()[0].airframe.inertia_body_kgm2);
}

TEST(PhysicsShards, OneShardIsExactlyTheComposedWorld) {
  const std::string path = write_world("grid10_one.xml", kGrid10);
  const std::vector<std::string> one = compose_world_shards(path, options(), 1);
  ASSERT_EQ(one.size(), 1u);
  EXPECT_EQ(one[0], compose_world(path, options()));
  // auto: 10 vehicles are too few to shard
  EXPECT_EQ(compose_world_shards(path, options(), 0).size(), 1u);
}

TEST(PhysicsShards, OutOfRangeCountsAreRefusedByName) {
  const std::string path = write_world("grid10_range.xml", kGrid10);
  for (int shards : {-1, kMaxPhysicsShards + 1, 11}) {  // 11 shards for 10 vehicles
    try {
      World::load(path, options(), ShardOptions{shards, 1});
      ADD_FAILURE() << shards << " shards were accepted";
    } catch (const WorldError& e) {
      EXPECT_NE(std::string(e.what()).find("shards"), std::string::npos) << e.what();
    }
  }
  for (int threads : {-1, kMaxPhysicsShards + 1}) {
    EXPECT_THROW(World::load(path, options(), ShardOptions{2, threads}), WorldError) << threads;
  }
}

TEST(PhysicsShards, WorldsWithOtherMovingThingsAreNotSharded) {
  // a loose crate (free joint) and a kinematic (mocap) platform: split from the vehicles in other
  // shards, they could not be touched by them, so such a world has one shard
  const std::string crate = write_world("crate.xml", kGrid10 + R"(
    <body name="crate" pos="20 20 1"><freejoint/><geom type="box" size="0.2 0.2 0.2"/></body>)");
  const std::string deck = write_world("deck.xml", kGrid10 + R"(
    <body name="deck" mocap="true" pos="20 20 1"><geom type="box" size="1 1 0.1"/></body>)");
  for (const auto& [path, body] : {std::pair{crate, "crate"}, std::pair{deck, "deck"}}) {
    try {
      World::load(path, options(), ShardOptions{2, 1});
      ADD_FAILURE() << path << " was sharded";
    } catch (const WorldError& e) {
      EXPECT_NE(std::string(e.what()).find(std::string("'") + body + "' moves"), std::string::npos)
          << e.what();
    }
    EXPECT_EQ(compose_world_shards(path, options(), 0).size(), 1u);
  }
  // static scenery is shared by every shard
  const std::string pole = write_world("pole.xml", kGrid10 + R"(
    <body name="pole" pos="20 20 0"><geom type="cylinder" size="0.1 2"/></body>)");
  EXPECT_EQ(World::load(pole, options(), ShardOptions{2, 1})->shard_count(), 2);
}

// Drops uav1 from 1 m onto uav0 standing on the ground (same x, y) and reports whether the two ever
// touched, and where uav1 ends up.
struct Drop {
  bool vehicles_touched = false;
  bool both_on_gear = false;  // at the end, each with landing-gear contact on static geometry
  double z0_m = 0, z1_m = 0;
};

Drop drop_one_quad_on_another(int shards) {
  const std::string path = write_world("stack.xml", R"(
    <uavsim_vehicle type="quad" name="uav0" pos="0 0 0"/>
    <uavsim_vehicle type="quad" name="uav1" pos="0 0 1"/>)");
  auto world = World::load(path, options(), ShardOptions{shards, 1});
  world->wake(0);
  Drop out;
  std::vector<VehicleContact> contacts;
  // free fall from 1 m: t = sqrt(2 h / g) = 0.45 s; then 1 s to settle
  for (int i = 0; i < 1500; ++i) {
    world->step();
    world->vehicle_contacts(&contacts);
    for (const VehicleContact& c : contacts)
      out.vehicles_touched = out.vehicles_touched || c.other_vehicle >= 0;
  }
  bool gear[2] = {false, false};
  for (const VehicleContact& c : contacts)
    gear[c.vehicle] = gear[c.vehicle] || (c.landing_gear && c.other_static);
  out.both_on_gear = gear[0] && gear[1];
  out.z0_m = world->truth(0).position_enu_m.z();
  out.z1_m = world->truth(1).position_enu_m.z();
  return out;
}

TEST(PhysicsShards, VehiclesInOneShardCollide) {
  const Drop d = drop_one_quad_on_another(1);
  EXPECT_TRUE(d.vehicles_touched);
  // uav1 landed on uav0 (or was knocked off it): never through it to the ground beneath
  EXPECT_NEAR(d.z0_m, kGearHeight_m, kRestTol_m);
}

TEST(PhysicsShards, VehiclesInDifferentShardsPassThroughEachOtherButStandOnTheGround) {
  const Drop d = drop_one_quad_on_another(2);
  EXPECT_FALSE(d.vehicles_touched);
  EXPECT_TRUE(d.both_on_gear);
  // both on their gear on the ground, one inside the other
  EXPECT_NEAR(d.z0_m, kGearHeight_m, kRestTol_m);
  EXPECT_NEAR(d.z1_m, kGearHeight_m, kRestTol_m);
}

}  // namespace
}  // namespace uavsim::server::physics
