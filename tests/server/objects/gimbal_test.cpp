#include "objects/gimbal.hpp"

#include <gtest/gtest.h>

#include "objects_fixture.hpp"
#include "uavsim/common/angles.hpp"

namespace uavsim::server::objects {
namespace {

using testing::make_shipped;

Eigen::Vector3d pointing_enu(sim::Simulation& sim, const Gimbal& g) {
  return physics::body_orientation_enu(sim.world(), g.body_id) * Eigen::Vector3d::UnitX();
}

TEST(Gimbal, DownLookingCameraStaysDownWhateverTheVehicleAttitude) {
  auto sim = make_shipped("mbzirc2017.xml");
  const ObjectSet set = add_world_objects(*sim);
  ASSERT_NE(set.gimbals, nullptr);
  const Gimbal& g = set.gimbals->gimbals()[0];
  EXPECT_EQ(g.mode, GimbalMode::kDown);
  // tilt the hexa 20 deg in roll and yaw it 40 deg; the camera still looks straight down
  const Eigen::Quaterniond q(Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitZ()) *
                             Eigen::AngleAxisd(0.35, Eigen::Vector3d::UnitX()));
  physics::set_vehicle_state(sim->world(), 0, Eigen::Vector3d(-40, -25, 5), q, Eigen::Vector3d::Zero(),
                             Eigen::Vector3d::Zero());
  sim->step();
  sim->step();
  EXPECT_LT((pointing_enu(*sim, g) - Eigen::Vector3d(0, 0, -1)).norm(), 1e-6);
  // mounted 0.09 m under the hull, following the vehicle
  EXPECT_LT((physics::body_position_enu_m(sim->world(), g.body_id) - sim->truth(0).position_enu_m).norm(),
            0.2);
}

TEST(Gimbal, ForwardCameraLooksLevelAlongTheHeadingAndTargetsPointIt) {
  auto sim = make_shipped("mbzirc2020.xml");
  const ObjectSet set = add_world_objects(*sim);
  ASSERT_NE(set.gimbals, nullptr);
  ASSERT_EQ(set.gimbals->gimbals().size(), 2u);
  Gimbal& g = set.gimbals->gimbals()[0];
  EXPECT_EQ(g.mode, GimbalMode::kForward);
  // pitched 15 deg nose down, heading north (yaw 90 deg): the camera looks level to the north
  const Eigen::Quaterniond q(Eigen::AngleAxisd(common::kPi / 2, Eigen::Vector3d::UnitZ()) *
                             Eigen::AngleAxisd(0.26, Eigen::Vector3d::UnitY()));
  physics::set_vehicle_state(sim->world(), 0, Eigen::Vector3d(-10, -27, 3), q, Eigen::Vector3d::Zero(),
                             Eigen::Vector3d::Zero());
  sim->step();
  sim->step();
  EXPECT_LT((pointing_enu(*sim, g) - Eigen::Vector3d(0, 1, 0)).norm(), 1e-6);
  // targets: 30 deg down, 90 deg to the left of the heading (west)
  g.mode = GimbalMode::kTargets;
  g.pitch_rad = -common::kPi / 6;
  g.yaw_rad = common::kPi / 2;
  sim->step();
  sim->step();
  EXPECT_LT((pointing_enu(*sim, g) - Eigen::Vector3d(-std::cos(common::kPi / 6), 0, -0.5)).norm(),
            1e-3);
}

}  // namespace
}  // namespace uavsim::server::objects
