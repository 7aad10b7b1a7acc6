// The world's GCS link settings (radio/gcs_radio_link.hpp): uavsim:gcs_link_backend,
// uavsim:gcs_position and the obstacle losses, each checked with an error naming the attribute.
#include <gtest/gtest.h>
#include <unistd.h>

#include <fstream>
#include <string>

#include "physics/object_bodies.hpp"
#include "radio/gcs_radio_link.hpp"

namespace uavsim::server::radio {
namespace {

constexpr double kHorizontalTol_m = 1e-6;
constexpr double kHeightTol_m = 1e-9;

// a world of one quad with the given <custom> elements, loaded from a temporary file
std::unique_ptr<physics::World> world_with(const std::string& custom) {
  const std::string path = ::testing::TempDir() + "gcs_world_" + std::to_string(getpid()) + ".xml";
  std::ofstream(path) << R"(<mujoco model="gcs"><compiler angle="radian"/><custom>)" << custom
                      << R"(</custom>
  <worldbody><geom type="plane" size="10 10 0.1"/>
  <uavsim_vehicle type="quad" name="uav0" pos="3 4 0"/></worldbody></mujoco>)";
  physics::ComposeOptions o;
  o.models_dir = UAVSIM_MODELS_DIR;
  auto w = physics::World::load(path, o);
  std::remove(path.c_str());
  return w;
}

TEST(GcsWorldSettings, TheWorldChoosesTheBackendAndPositionUnlessGiven) {
  auto w = world_with(R"(<text name="uavsim:gcs_link_backend" data="ns3"/>
    <numeric name="uavsim:gcs_position" data="1 2 3"/>
    <numeric name="uavsim:radio_obstacle_loss_db" data="0 0 0 40"/>)");
  bool ns3 = false;
  GcsRadioOptions o;
  apply_world_gcs_settings(*w, false, &ns3, &o);
  EXPECT_TRUE(ns3);
  ASSERT_TRUE(o.gcs_position_enu_m);
  EXPECT_EQ(*o.gcs_position_enu_m, Eigen::Vector3d(1, 2, 3));
  EXPECT_EQ(o.config.obstacle_loss_db[3], 40.0);
  // the command line's choices stand
  ns3 = false;
  GcsRadioOptions given;
  given.gcs_position_enu_m = Eigen::Vector3d(7, 8, 9);
  apply_world_gcs_settings(*w, true, &ns3, &given);
  EXPECT_FALSE(ns3);
  EXPECT_EQ(*given.gcs_position_enu_m, Eigen::Vector3d(7, 8, 9));
}

TEST(GcsWorldSettings, MalformedOrOutOfRangeAttributesAreNamed) {
  for (const char* custom : {R"(<numeric name="uavsim:gcs_position" data="1 2"/>)",
                             R"(<numeric name="uavsim:gcs_position" data="1 2 3 4"/>)",
                             R"(<numeric name="uavsim:gcs_position" data="1 2 200000"/>)"}) {
    auto w = world_with(custom);
    bool ns3 = false;
    GcsRadioOptions o;
    try {
      apply_world_gcs_settings(*w, false, &ns3, &o);
      ADD_FAILURE() << custom;
    } catch (const physics::WorldError& e) {
      EXPECT_NE(std::string(e.what()).find("uavsim:gcs_position"), std::string::npos) << e.what();
    }
  }
  auto w = world_with(R"(<text name="uavsim:gcs_link_backend" data="wifi"/>)");
  bool ns3 = false;
  GcsRadioOptions o;
  EXPECT_THROW(apply_world_gcs_settings(*w, false, &ns3, &o), physics::WorldError);
}

TEST(GcsWorldSettings, TheDefaultGroundStationStandsAboveTheVehiclesStart) {
  auto w = world_with("");
  sim::Simulation sim(std::move(w), sim::SimConfig{});
  const Eigen::Vector3d g = default_gcs_position(sim);
  EXPECT_NEAR(g.x(), 3.0, kHorizontalTol_m);
  EXPECT_NEAR(g.y(), 4.0, kHorizontalTol_m);
  EXPECT_NEAR(g.z(), sim.truth(0).position_enu_m.z() + kGcsAntennaHeight_m, kHeightTol_m);
  EXPECT_FALSE(validate_gcs_position(Eigen::Vector3d(0, 0, 100001)).empty());
  EXPECT_TRUE(validate_gcs_position(Eigen::Vector3d(-100000, 0, 0)).empty());
}

}  // namespace
}  // namespace uavsim::server::radio
