// Which cameras and geoms are a vehicle's (app/camera_owners.hpp), in the MBZIRC 2020 world: two
// quads, each with a gimbal carrying its front camera.
#include "app/camera_owners.hpp"

#include <gtest/gtest.h>

#include "../sim/sim_fixture.hpp"
#include "objects/gimbal.hpp"

namespace uavsim::server::app {
namespace {

TEST(CameraOwners, NameEveryVehicleRootAndTheGimbalsCarryingTheirCameras) {
  const auto world = sim::testing::make_sim("mbzirc2020.xml");
  sim::Simulation& s = *world;
  const objects::ObjectSet objects = objects::add_world_objects(s);
  const render::CameraOwners owners = camera_owners(s.world(), objects);
  ASSERT_EQ(owners.vehicle_root_bodies.size(), s.vehicle_count());
  for (size_t i = 0; i < s.vehicle_count(); ++i) {
    EXPECT_EQ(owners.vehicle_root_bodies[i].first, s.world().vehicles()[i].body_id);
    EXPECT_EQ(owners.vehicle_root_bodies[i].second, s.vehicle_name(i));
  }
  ASSERT_NE(objects.gimbals, nullptr);
  ASSERT_EQ(owners.gimbal_body_vehicle.size(), objects.gimbals->gimbals().size());
  for (const objects::Gimbal& g : objects.gimbals->gimbals())
    EXPECT_EQ(owners.gimbal_body_vehicle.at(g.body_id), g.vehicle);
}

// a world without objects: the vehicles only
TEST(CameraOwners, WithoutGimbalsOnlyTheVehicles) {
  const auto world = sim::testing::make_sim("mbzirc2020.xml");
  sim::Simulation& s = *world;
  const render::CameraOwners owners = camera_owners(s.world(), objects::ObjectSet{});
  EXPECT_EQ(owners.vehicle_root_bodies.size(), s.vehicle_count());
  EXPECT_TRUE(owners.gimbal_body_vehicle.empty());
}

}  // namespace
}  // namespace uavsim::server::app
