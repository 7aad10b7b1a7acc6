// Parking (physics/world.hpp, sim/simulation.hpp): vehicles at rest on static geometry are held
// exactly in place without contact constraints, and wake when they arm, are touched, or are moved.
#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include <cstring>
#include <fstream>

#include "grid_flight.hpp"
#include "physics/world.hpp"
#include "sim/simulation.hpp"
#include "sim_fixture.hpp"

namespace uavsim::server::sim {
namespace {

using testing::make_sim;
using testing::take_off;

const std::string kThreeQuads = std::string(UAVSIM_TEST_DATA_DIR) + "/worlds/three_quads.xml";

// the vehicle's 7 free-joint qpos, bit for bit
std::vector<double> qpos_of(Simulation& sim, size_t vehicle) {
  const mjData* d = sim.world().data();
  const int adr = sim.world().vehicles()[vehicle].qpos_adr;
  return std::vector<double>(d->qpos + adr, d->qpos + adr + 7);
}

TEST(Parking, AVehicleThatStartsOnTheGroundIsParkedAndHeldExactly) {
  auto sim = make_sim("empty.xml");
  ASSERT_TRUE(sim->world().parked(0));
  const std::vector<double> start = qpos_of(*sim, 0);
  sim->run_until(10.0);
  EXPECT_TRUE(sim->world().parked(0));
  EXPECT_EQ(qpos_of(*sim, 0), start);       // exactly: not a micrometre of creep
  EXPECT_EQ(sim->world().data()->nefc, 0);  // and no constraint rows for it
  // the flight controller sees a vehicle at rest on the ground: ready to arm, nothing recorded
  EXPECT_TRUE(sim->fc(0).prearm_ok());
  EXPECT_TRUE(sim->truth(0).on_ground);
  EXPECT_EQ(sim->events().recent().size(), 0u);
}

TEST(Parking, AVehicleInTheAirIsNotParked) {
  const std::string path = ::testing::TempDir() + "/parking_air.xml";
  std::ofstream(path) << R"(<mujoco><compiler angle="radian"/><worldbody>
    <geom name="ground" type="plane" size="50 50 0.1"/>
    <uavsim_vehicle type="quad" name="high" pos="0 0 10"/>
    <uavsim_vehicle type="quad" name="low" pos="4 0 0"/></worldbody></mujoco>)";
  physics::ComposeOptions o;
  o.models_dir = UAVSIM_MODELS_DIR;
  Simulation sim(physics::World::load(path, o), SimConfig{});
  EXPECT_FALSE(sim.world().parked(0));
  EXPECT_TRUE(sim.world().parked(1));
  // it falls 10 m: sqrt(2 h / g) = 1.43 s; a 14 m/s touchdown is a crash, and the wreck then parks
  sim.run_until(5.0);
  EXPECT_EQ(sim.events().count(EventType::kCrash), 1u);
  EXPECT_TRUE(sim.world().parked(0));
  EXPECT_TRUE(sim.world().parked(1));
}

TEST(Parking, AParkedVehicleWakesWhenItArmsAndTakesOffNormally) {
  auto sim = make_sim("empty.xml");
  ASSERT_TRUE(sim->world().parked(0));
  take_off(*sim, 5.0);  // asserts the climb to within 0.3 m of 5 m
  EXPECT_FALSE(sim->world().parked(0));
  EXPECT_EQ(sim->events().count(EventType::kCrash), 0u);
  EXPECT_EQ(sim->events().count(EventType::kTakeoff), 1u);
}

TEST(Parking, ALandedVehicleParksOnceDisarmedAndStill) {
  auto sim = make_sim("empty.xml");
  take_off(*sim, 3.0);
  sim->post(0, [](fc::FlightController& f) { f.land(); });
  const double deadline = sim->time_s() + 30.0;
  while (sim->fc(0).armed() && sim->time_s() < deadline) sim->step();
  ASSERT_FALSE(sim->fc(0).armed()) << "never disarmed after landing";
  EXPECT_FALSE(sim->world().parked(0));  // the motors are still spinning down
  sim->run_until(sim->time_s() + 2.0);
  ASSERT_TRUE(sim->world().parked(0));
  const std::vector<double> held = qpos_of(*sim, 0);
  sim->run_until(sim->time_s() + 2.0);
  EXPECT_EQ(qpos_of(*sim, 0), held);
  // and it flies again from where it stands
  take_off(*sim, 3.0);
  EXPECT_EQ(sim->events().count(EventType::kCrash), 0u);
}

TEST(Parking, AParkedVehicleWakesWhenSomethingHitsIt) {
  physics::ComposeOptions o;
  o.models_dir = UAVSIM_MODELS_DIR;
  Simulation sim(physics::World::load(kThreeQuads, o), SimConfig{});
  ASSERT_TRUE(sim.world().parked(1));
  const Eigen::Vector3d parked_at = sim.truth(1).position_enu_m;
  // uav0 lifts to 0.2 m and flies into uav1, 4 m east of it, at hull height
  take_off(sim, 0.3, 0);
  testing::goto_enu(sim, parked_at + Eigen::Vector3d(0.5, 0, 0.05), 0);
  const double deadline = sim.time_s() + 20.0;
  while (sim.events().count(EventType::kCrash) < 2 && sim.time_s() < deadline) sim.step();
  // both crashed (a vehicle-vehicle contact), and uav1 was woken and pushed
  EXPECT_EQ(sim.events().count(EventType::kCrash), 2u);
  sim.run_until(sim.time_s() + 0.1);
  EXPECT_GT((sim.world().truth(1).position_enu_m - parked_at).norm(), 1e-3);
  EXPECT_TRUE(sim.world().parked(2));  // the bystander never woke
}

TEST(Parking, ResetParksTheVehiclesAgain) {
  auto sim = make_sim("empty.xml");
  take_off(*sim, 2.0);
  sim->reset(3);
  EXPECT_TRUE(sim->world().parked(0));
  EXPECT_EQ(sim->world().parked_count(), 1u);
}

TEST(Parking, AHundredQuadGridStartsParkedAndTenOfThemTakeOff) {
  const std::string path = ::testing::TempDir() + "/parking_grid.xml";
  std::ofstream(path)
      << "<mujoco><compiler angle=\"radian\"/><option timestep=\"0.001\"/><worldbody>"
      << "<geom name=\"ground\" type=\"plane\" size=\"500 500 0.1\"/>"
      << "<uavsim_grid type=\"quad\" rows=\"10\" cols=\"10\" spacing=\"4\" collision=\"lean\"/>"
      << "</worldbody></mujoco>";
  testing::fly_some_of_a_grid(path, 100, 10);
}

}  // namespace
}  // namespace uavsim::server::sim
