#include "sim/simulation.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <thread>

#include "sim_fixture.hpp"

namespace uavsim::server::sim {
namespace {

constexpr double kTimeTol_s = 1e-12;
using testing::goto_enu;
using testing::make_sim;
using testing::take_off;

const std::string kThreeQuads = std::string(UAVSIM_TEST_DATA_DIR) + "/worlds/three_quads.xml";

// flies a short fixed script and returns the state hash after 30 s of sim time
uint64_t scripted_hash(uint64_t seed) {
  auto sim = make_sim("empty.xml", seed);
  take_off(*sim, 8.0);
  goto_enu(*sim, Eigen::Vector3d(5, -3, 9));
  sim->run_until(30.0);
  return sim->state_hash();
}

TEST(Simulation, SameSeedGivesBitIdenticalStateAfter30s) {
  EXPECT_EQ(scripted_hash(7), scripted_hash(7));
}

TEST(Simulation, DifferentSeedGivesDifferentNoiseAndState) {
  EXPECT_NE(scripted_hash(7), scripted_hash(8));
}

TEST(Simulation, ControlRateIsAnIntegerDivisorOfThePhysicsRate) {
  auto sim = make_sim("empty.xml");
  EXPECT_EQ(sim->control_decimation(), 2);  // 1000 / 500
  EXPECT_DOUBLE_EQ(sim->physics_dt_s(), 0.001);
  physics::ComposeOptions o;
  o.models_dir = UAVSIM_MODELS_DIR;
  SimConfig c;
  // 1000 / 400 = 2.5 physics steps per control step: rounded half away from zero to every 3 steps
  // (333.3 Hz), a whole number so the control rate never drifts
  c.control_hz = 400.0;
  Simulation s(physics::World::load(std::string(UAVSIM_MODELS_DIR) + "/worlds/empty.xml", o), c);
  EXPECT_EQ(s.control_decimation(), 3);
}

TEST(Simulation, TasksRunAtTheNextControlBoundaryInVehicleOrder) {
  physics::ComposeOptions o;
  o.models_dir = UAVSIM_MODELS_DIR;
  Simulation sim(physics::World::load(kThreeQuads, o), SimConfig{});
  sim.step();  // now mid control period (decimation 2)
  std::vector<std::pair<size_t, double>> order;
  // posted in reverse vehicle order, from another thread
  std::thread poster([&] {
    for (size_t v : {2u, 1u, 0u}) sim.post(v, [&order, v, &sim](fc::FlightController&) {
      order.push_back({v, sim.time_s()});
    });
  });
  poster.join();
  EXPECT_FALSE(sim.post(3, [](fc::FlightController&) {}));  // unknown vehicle
  sim.step();  // step 1 -> 2: no control step yet
  EXPECT_TRUE(order.empty());
  sim.step();  // step 2 is a control boundary
  ASSERT_EQ(order.size(), 3u);
  EXPECT_EQ(order[0].first, 0u);
  EXPECT_EQ(order[1].first, 1u);
  EXPECT_EQ(order[2].first, 2u);
  EXPECT_NEAR(order[0].second, 0.002, kTimeTol_s);
}

TEST(Simulation, VehiclesThatCollideAreBothCrashed) {
  physics::ComposeOptions o;
  o.models_dir = UAVSIM_MODELS_DIR;
  Simulation sim(physics::World::load(kThreeQuads, o), SimConfig{});
  take_off(sim, 5.0, 0);
  take_off(sim, 5.0, 1);
  // steer uav0 into uav1: every 50 ms its target is uav1's true position expressed in uav0's own
  // estimate (each estimate has its own offset of some cm and the hulls are only 7 cm tall)
  const double end = sim.time_s() + 10.0;
  while (sim.time_s() < end && !sim.runtime(0).crashed) {
    const Eigen::Vector3d offset = sim.truth(1).position_enu_m - sim.truth(0).position_enu_m;
    goto_enu(sim, sim.fc(0).estimate().position_enu_m + offset, 0);
    for (int i = 0; i < 50; ++i) sim.step();
  }
  ASSERT_GE(sim.events().count(EventType::kCrash), 2u);
  EXPECT_TRUE(sim.runtime(0).crashed);
  EXPECT_TRUE(sim.runtime(1).crashed);
  EXPECT_FALSE(sim.fc(0).armed());
  EXPECT_FALSE(sim.runtime(2).crashed);  // the others are unaffected
}

TEST(Simulation, FallingOutOfTheSkyIsAHardImpact) {
  auto sim = make_sim("empty.xml");
  take_off(*sim, 10.0);
  sim->kill_vehicle(0, "killed by test");  // motors off at 10 m
  sim->run_until(sim->time_s() + 5.0);
  ASSERT_EQ(sim->events().count(EventType::kCrash), 1u);  // killed once; the impact adds nothing
  EXPECT_LT(sim->truth(0).position_enu_m.z(), 0.5);
}

TEST(Simulation, HardLandingFromGearContactIsACrash) {
  auto sim = make_sim("empty.xml");
  // drop the idle vehicle level from 3 m: v = sqrt(2 g h) = 7.7 m/s > 3 m/s
  const double pos[3] = {0, 0, 3.0};
  const double quat[4] = {1, 0, 0, 0};
  sim->world().set_pose(0, pos, quat);
  sim->run_until(2.0);
  ASSERT_EQ(sim->events().count(EventType::kCrash), 1u);
  for (const Event& e : sim->events().recent()) {
    if (e.type == EventType::kCrash) EXPECT_NE(e.detail.find("hard landing"), std::string::npos) << e.detail;
  }
}

TEST(Simulation, CommandedArmingAndModeChangesAreEvents) {
  auto sim = make_sim("empty.xml");
  take_off(*sim, 3.0);  // GUIDED + arm in one control step
  ASSERT_EQ(sim->events().count(EventType::kArmed), 1u);
  ASSERT_EQ(sim->events().count(EventType::kModeChange), 1u);
  for (const Event& e : sim->events().recent()) {
    if (e.type == EventType::kModeChange) EXPECT_EQ(e.detail, "GUIDED");
  }
}

TEST(Simulation, TakeoffAndTouchdownEventsFollowGroundContact) {
  auto sim = make_sim("empty.xml");
  take_off(*sim, 3.0);
  sim->post(0, [](fc::FlightController& f) { f.land(); });
  sim->run_until(sim->time_s() + 30.0);
  EXPECT_GE(sim->events().count(EventType::kTakeoff), 1u);
  EXPECT_GE(sim->events().count(EventType::kTouchdown), 1u);
  EXPECT_EQ(sim->events().count(EventType::kCrash), 0u);
}

}  // namespace
}  // namespace uavsim::server::sim
