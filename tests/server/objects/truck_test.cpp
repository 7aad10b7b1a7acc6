#include "objects/truck.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "objects_fixture.hpp"

namespace uavsim::server::objects {
namespace {

using testing::make_shipped;
using testing::make_world;

constexpr double kSpeedTol = 0.02;     // +-2% of the nominal speed
constexpr double kOnTrackTol_m = 0.1;  // the truck's origin stays this close to the eight's centre line
constexpr double kPosTol_m = 1e-9;

Eigen::Vector3d truck_position(sim::Simulation& sim, const Truck& truck) {
  return physics::body_position_enu_m(sim.world(), sim.world().body_id(truck.params().name));
}

TEST(Truck, ShippedWorldHasTheMbzirc2017TrackAndSchedule) {
  auto sim = make_shipped("mbzirc2017.xml");
  const ObjectSet set = add_world_objects(*sim);
  ASSERT_EQ(set.trucks.size(), 1u);
  const TruckParams& p = set.trucks[0]->params();
  EXPECT_DOUBLE_EQ(p.track.circle_radius_m, 20.0);
  EXPECT_DOUBLE_EQ(p.track.centre_separation_m, 45.0);
  EXPECT_DOUBLE_EQ(p.speed.speed1_m_s, 15.0 / 3.6);
  EXPECT_DOUBLE_EQ(p.speed.speed2_m_s, 5.0 / 3.6);
  EXPECT_DOUBLE_EQ(p.speed.switch_time_s, 480.0);
  EXPECT_NEAR(set.trucks[0]->deck_height_m(), 1.5, kPosTol_m);
}

TEST(Truck, DrivesTheEightAtFifteenThenFiveKmh) {
  // the 8 min switch moved to 3 s so the test sees both speeds in 6 s of sim time
  auto sim = make_world("truck_speed", R"(<uavsim_object type="truck" name="truck"/>)",
                        R"(<numeric name="uavsim:truck:speed" data="15 5 3 0"/>)");
  const ObjectSet set = add_world_objects(*sim);
  const Truck& truck = *set.trucks[0];
  Eigen::Vector3d last = truck_position(*sim, truck);
  double last_t = sim->time_s();
  while (sim->time_s() < 6.0 - 1e-9) {
    sim->step();
    const Eigen::Vector3d p = truck_position(*sim, truck);
    ASSERT_LT(truck.track().distance_m(p.head<2>()), kOnTrackTol_m) << "t = " << sim->time_s();
    ASSERT_NEAR(p.z(), 0.0, kPosTol_m);
    // average speed over each 0.5 s window away from the switch (a chord on a 20 m circle is shorter
    // than the arc by < 0.01%)
    if (sim->time_s() - last_t >= 0.5 - 1e-9) {
      const double speed = (p - last).norm() / (sim->time_s() - last_t);
      if (sim->time_s() <= 3.0) EXPECT_NEAR(speed, 15.0 / 3.6, kSpeedTol * 15.0 / 3.6) << sim->time_s();
      if (last_t >= 3.0) EXPECT_NEAR(speed, 5.0 / 3.6, kSpeedTol * 5.0 / 3.6) << sim->time_s();
      last = p;
      last_t = sim->time_s();
    }
  }
  EXPECT_DOUBLE_EQ(truck.state(sim->time_s()).speed_m_s, 5.0 / 3.6);
}

TEST(Truck, StaysOnTheEightAndInsideTheArenaForALap) {
  // the ideal track: the shipped world's driver off (truck_driver_test.cpp covers the wander)
  auto sim = make_world("truck_lap", R"(<uavsim_object type="truck" name="truck"/>)",
                        R"(<numeric name="uavsim:truck:speed" data="15 5 480 0"/>)");
  const ObjectSet set = add_world_objects(*sim);
  const Truck& truck = *set.trucks[0];
  // one lap (254.5 m at 4.167 m/s = 61 s), checked on the truck's state at every step time
  for (double t = 0.0; t < 62.0; t += 0.01) {
    const TruckState s = truck.state(t);
    ASSERT_LT(truck.track().distance_m(s.position_enu_m.head<2>()), kOnTrackTol_m) << t;
    ASSERT_LE(std::abs(s.position_enu_m.x()), 45.0);
    ASSERT_LE(std::abs(s.position_enu_m.y()), 30.0);
  }
  EXPECT_EQ(truck.state(62.0).laps, 1);
  sim->run_until(2.0);
  EXPECT_LT((truck_position(*sim, truck) - truck.state(sim->time_s() - sim->physics_dt_s()).position_enu_m)
                .norm(), 1e-9);
}

// a quad world with the truck (default track and speeds)
std::unique_ptr<sim::Simulation> quad_and_truck(const std::string& label, const std::string& speed) {
  return make_world(label,
                    R"(<uavsim_object type="truck" name="truck"/>
                       <uavsim_vehicle type="quad" name="uav0" pos="-30 -20 0"/>)",
                    R"(<numeric name="uavsim:truck:speed" data=")" + speed + R"("/>)");
}

// puts the quad's skids 5 mm above the deck centre, moving at velocity_enu_m_s
void place_on_deck(sim::Simulation& sim, const Truck& truck, const Eigen::Vector3d& velocity_enu_m_s) {
  const TruckState s = truck.state(sim.time_s());
  // skids: capsules 0.15 m below the body origin with radius 0.01
  const Eigen::Vector3d p = s.deck_centre_enu_m + Eigen::Vector3d(0, 0, 0.16 + 0.005);
  physics::set_vehicle_state(sim.world(), 0, p,
                             Eigen::Quaterniond(Eigen::AngleAxisd(s.yaw_rad, Eigen::Vector3d::UnitZ())),
                             velocity_enu_m_s, Eigen::Vector3d::Zero());
}

TEST(Truck, SoftTouchdownOnTheDeckLandsAndTheVehicleRidesAlong) {
  auto sim = quad_and_truck("truck_ride", "15 5 480 0");
  const ObjectSet set = add_world_objects(*sim);
  const Truck& truck = *set.trucks[0];
  sim->run_until(1.0);
  // matching the truck's velocity: the skids meet the deck at ~0.3 m/s (5 mm of free fall)
  place_on_deck(*sim, truck, truck.state(sim->time_s()).velocity_enu_m_s);
  sim->run_until(1.2);
  ASSERT_EQ(sim->events().count(sim::EventType::kLandedOnTarget), 1u);
  const sim::Event& landed = sim->events().recent().back();
  EXPECT_EQ(landed.vehicle, 0);

  // ride 10 s (42 m of track, round the right circle): the quad stays where it landed on the deck
  const auto offset = [&] {
    const TruckState s = truck.state(sim->time_s() - sim->physics_dt_s());
    const Eigen::Vector3d r = sim->truth(0).position_enu_m - s.deck_centre_enu_m;
    return Eigen::Vector3d(Eigen::AngleAxisd(-s.yaw_rad, Eigen::Vector3d::UnitZ()) * r);
  };
  const Eigen::Vector3d start_offset = offset();
  const Eigen::Vector3d start = sim->truth(0).position_enu_m;
  while (sim->time_s() < 11.2) {
    sim->step();
    ASSERT_LT((offset() - start_offset).norm(), 0.01) << "t = " << sim->time_s();
  }
  EXPECT_GT((sim->truth(0).position_enu_m - start).norm(), 30.0);
  EXPECT_EQ(sim->events().count(sim::EventType::kCrash), 0u);
  EXPECT_EQ(truck.state(sim->time_s()).carried_vehicles, std::vector<int>{0});
}

TEST(Truck, TouchdownFastRelativeToTheDeckIsNotALanding) {
  auto sim = quad_and_truck("truck_fast", "15 5 480 0");
  const ObjectSet set = add_world_objects(*sim);
  const Truck& truck = *set.trucks[0];
  sim->run_until(1.0);
  // standing still while the deck passes underneath at 4.2 m/s
  place_on_deck(*sim, truck, Eigen::Vector3d::Zero());
  sim->run_until(1.2);
  EXPECT_EQ(sim->events().count(sim::EventType::kLandedOnTarget), 0u);
  EXPECT_EQ(sim->events().count(sim::EventType::kCrash), 0u);  // deck contact is not a crash
  EXPECT_TRUE(truck.state(sim->time_s()).carried_vehicles.empty());
}

TEST(Truck, ResetDropsCarriedVehiclesAndRestartsTheSchedule) {
  auto sim = quad_and_truck("truck_reset", "15 5 480 0");
  const ObjectSet set = add_world_objects(*sim);
  const Truck& truck = *set.trucks[0];
  sim->run_until(1.0);
  place_on_deck(*sim, truck, truck.state(sim->time_s()).velocity_enu_m_s);
  sim->run_until(1.5);
  ASSERT_FALSE(truck.state(sim->time_s()).carried_vehicles.empty());
  sim->reset(2);
  EXPECT_TRUE(truck.state(sim->time_s()).carried_vehicles.empty());
  sim->step();
  EXPECT_LT(truck_position(*sim, truck).head<2>().norm(), 1e-9);  // s = 0: the crossing
}

TEST(Truck, QuadFlownOntoTheDeckLandsAndIsCarriedWhenTheTruckStarts) {
  // the truck waits at the crossing for 40 s, then drives at 5 km/h
  auto sim = make_world("truck_fly",
                        R"(<uavsim_object type="truck" name="truck"/>
                           <uavsim_vehicle type="quad" name="uav0" pos="-6 -6 0"/>)",
                        R"(<numeric name="uavsim:truck:speed" data="0 5 40 0"/>)");
  const ObjectSet set = add_world_objects(*sim);
  const Truck& truck = *set.trucks[0];
  ASSERT_TRUE(testing::take_off(*sim, 4.0));
  sim->post(0, [](fc::FlightController& f) {
    fc::GuidedTarget t;
    t.position_enu_m = Eigen::Vector3d(0, 0, 4.0);
    f.set_guided_target(t);
  });
  sim->run_until(sim->time_s() + 10.0);
  ASSERT_LT(sim->truth(0).position_enu_m.head<2>().norm(), 0.3) << "did not reach the deck";
  sim->post(0, [](fc::FlightController& f) { f.land(); });
  while (sim->time_s() < 39.9 && sim->events().count(sim::EventType::kLandedOnTarget) == 0) sim->step();
  ASSERT_EQ(sim->events().count(sim::EventType::kLandedOnTarget), 1u);
  EXPECT_EQ(sim->events().count(sim::EventType::kCrash), 0u);
  sim->run_until(52.0);
  // 12 s at 5 km/h = 16.7 m along the track; the quad went with the deck
  const TruckState s = truck.state(sim->time_s());
  EXPECT_GT(s.position_enu_m.head<2>().norm(), 10.0);
  EXPECT_LT((sim->truth(0).position_enu_m - s.deck_centre_enu_m).head<2>().norm(), 0.5);
  EXPECT_EQ(sim->events().count(sim::EventType::kCrash), 0u);
}

}  // namespace
}  // namespace uavsim::server::objects
