// The non-finite-state rule (the style notes; Simulation's "sim.nonfinite_rule" entries of the step
// schedule): a vehicle whose state or rotor force goes non-finite or runs away at run time has its
// controls zeroed, is killed and put back once, with one state_fault event; the world (its clock, the
// other vehicles) goes on.
#include <gtest/gtest.h>

#include <limits>

#include "sim_fixture.hpp"

namespace uavsim::server::sim {
namespace {

// the other vehicle's hover height through the fault
constexpr double kHoverAltTol_m = 0.3;

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
  EXPECT_NEAR(sim->truth(1).position_enu_m.z(), z1, kHoverAltTol_m);
  EXPECT_TRUE(sim->fc(1).armed());
  // a second runaway of the dead vehicle is put back again, without another event
  sim->world().set_pose(0, far, level);
  for (int k = 0; k < 100; ++k) sim->step();
  EXPECT_EQ(sim->events().count(EventType::kStateFault), 1u);
  EXPECT_TRUE(sim->truth(0).position_enu_m.allFinite());
  EXPECT_LT((sim->truth(0).position_enu_m - start0).norm(), 0.5);
}

// vehicle 0 faulted once by what was injected: killed and put back at rest where it started, one
// state_fault event with the reason, the clock not reset (MuJoCo's own check would have reset the whole
// world to t = 0), vehicle 1 still hovering at z1
void expect_rule_applied(Simulation& sim, const std::string& reason, double t0, double z1) {
  EXPECT_EQ(sim.events().count(EventType::kStateFault), 1u);
  EXPECT_EQ(sim.events().count(EventType::kCrash), 0u);
  for (const Event& e : sim.events().recent()) {
    if (e.type == EventType::kStateFault) {
      EXPECT_EQ(e.vehicle, 0);
      EXPECT_EQ(e.detail, reason);
    }
  }
  EXPECT_TRUE(sim.runtime(0).crashed);
  EXPECT_FALSE(sim.fc(0).armed());
  for (double cmd : sim.runtime(0).motor_cmd) EXPECT_EQ(cmd, 0.0);
  const fc::TruthState t = sim.truth(0);
  EXPECT_TRUE(t.position_enu_m.allFinite() && t.velocity_enu_m_s.allFinite());
  EXPECT_LT((t.position_enu_m - sim.runtime(0).start_position_enu_m).norm(), 0.5);
  EXPECT_GT(sim.time_s(), t0);
  EXPECT_NEAR(sim.truth(1).position_enu_m.z(), z1, kHoverAltTol_m);
  EXPECT_TRUE(sim.fc(1).armed());
}

TEST(StateFault, NaNStateAfterMjStepIsCaughtBeforeTheNextStep) {
  auto sim = testing::make_sim("mbzirc2020.xml");
  testing::take_off(*sim, 3.0, 0);  // flying, not parked
  testing::take_off(*sim, 3.0, 1);
  const double z1 = sim->truth(1).position_enu_m.z();
  const double t0 = sim->time_s();
  // a NaN position right after one mj_step, as a numerical blow-up inside it would leave (registered in
  // the mj_step phase, so the rule in the contacts phase sees it the same step)
  bool injected = false;
  sim->schedule().add(Phase::kPhysics, "test.inject_nan", [&] {
    if (injected) return;
    injected = true;
    const double nan = std::numeric_limits<double>::quiet_NaN();
    const double bad[3] = {nan, 0.0, 0.0};
    const double level[4] = {1.0, 0.0, 0.0, 0.0};
    sim->world().set_pose(0, bad, level);
  });
  sim->step();
  ASSERT_TRUE(injected);
  // put back within the step that went bad
  EXPECT_TRUE(sim->truth(0).position_enu_m.allFinite());
  for (int k = 0; k < 500; ++k) sim->step();
  expect_rule_applied(*sim, "non-finite or runaway state", t0, z1);
}

TEST(StateFault, NaNRotorForceIsNeverAppliedAndFaultsTheVehicle) {
  auto sim = testing::make_sim("mbzirc2020.xml");
  testing::take_off(*sim, 3.0, 0);
  testing::take_off(*sim, 3.0, 1);
  const double z1 = sim->truth(1).position_enu_m.z();
  const double t0 = sim->time_s();
  // a NaN reaction-torque coefficient: vehicle 0's rotor wrench becomes non-finite (and stays so: NaN
  // times the zeroed thrust is NaN), so it must never reach qfrc_applied
  sim->world().mutable_airframe(0).rotors[0].torque_coef_m = std::numeric_limits<double>::quiet_NaN();
  for (int k = 0; k < 500; ++k) sim->step();
  expect_rule_applied(*sim, "non-finite or runaway rotor force", t0, z1);
}

}  // namespace
}  // namespace uavsim::server::sim
