// A vehicle whose state runs away at run time is killed and put back once, with one event; the world
// (its clock, the other vehicles) goes on.
#include <gtest/gtest.h>

#include "sim_fixture.hpp"

namespace uavsim::server::sim {
namespace {

TEST(StateFault, RunawayVehicleIsKilledAndPutBackOnceWhileTheOtherFliesOn) {
  auto sim = testing::make_sim("mbzirc2020.xml");
  testing::take_off(*sim, 3.0, 1);
  const Eigen::Vector3d start0 = sim->runtime(0).start_position_enu_m;
  const double z1 = sim->truth(1).position_enu_m.z();
  const double t0 = sim->time_s();
  // vehicle 0 thrown 1e7 m away: finite, far below MuJoCo's own reset threshold, far past any flight
  const double far[3] = {1e7, 0.0, 0.0};
  const double level[4] = {1.0, 0.0, 0.0, 0.0};
  sim->world().set_pose(0, far, level);
  for (int k = 0; k < 500; ++k) sim->step();
  EXPECT_EQ(sim->events().count(EventType::kStateFault), 1u);
  EXPECT_EQ(sim->events().count(EventType::kCrash), 0u);
  EXPECT_TRUE(sim->runtime(0).crashed);
  EXPECT_FALSE(sim->fc(0).armed());
  EXPECT_LT((sim->truth(0).position_enu_m - start0).norm(), 0.5);
  // the clock was not reset and vehicle 1 still hovers
  EXPECT_GT(sim->time_s(), t0);
  EXPECT_NEAR(sim->truth(1).position_enu_m.z(), z1, 0.3);
  EXPECT_TRUE(sim->fc(1).armed());
  // a second runaway of the dead vehicle is put back again, without another event
  sim->world().set_pose(0, far, level);
  for (int k = 0; k < 100; ++k) sim->step();
  EXPECT_EQ(sim->events().count(EventType::kStateFault), 1u);
  EXPECT_TRUE(sim->truth(0).position_enu_m.allFinite());
  EXPECT_LT((sim->truth(0).position_enu_m - start0).norm(), 0.5);
}

}  // namespace
}  // namespace uavsim::server::sim
