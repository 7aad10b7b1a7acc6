#include "objects/balloons.hpp"

#include <gtest/gtest.h>

#include "objects_fixture.hpp"

namespace uavsim::server::objects {
namespace {

constexpr double kPosTol_m = 1e-9;
constexpr double kPopTimeTol_s = 0.01;

using testing::drive_step;
using testing::make_shipped;
using testing::make_world;

std::vector<Eigen::Vector3d> positions(const BalloonField& field) {
  std::vector<Eigen::Vector3d> out;
  for (const BalloonState& b : field.balloons()) out.push_back(b.position_enu_m);
  return out;
}

TEST(Balloons, PositionsComeFromTheSeed) {
  auto a = make_shipped("mbzirc2020.xml", 3);
  auto b = make_shipped("mbzirc2020.xml", 3);
  auto c = make_shipped("mbzirc2020.xml", 4);
  const ObjectSet sa = add_world_objects(*a), sb = add_world_objects(*b), sc = add_world_objects(*c);
  ASSERT_EQ(sa.balloons->balloons().size(), 5u);
  EXPECT_EQ(positions(*sa.balloons), positions(*sb.balloons));
  const auto pc = positions(*sc.balloons);
  for (size_t i = 0; i < pc.size(); ++i) EXPECT_NE(positions(*sa.balloons)[i], pc[i]) << i;
  // reset(4) gives what a fresh seed-4 world has
  a->reset(4);
  EXPECT_EQ(positions(*sa.balloons), pc);
}

TEST(Balloons, PlacementRespectsTheArenaSpacingAndVehicleClearance) {
  for (uint64_t seed = 1; seed <= 20; ++seed) {
    auto sim = make_shipped("mbzirc2020.xml", seed);
    const ObjectSet set = add_world_objects(*sim);
    const auto p = positions(*set.balloons);
    for (size_t i = 0; i < p.size(); ++i) {
      // uavsim:balloon_arena = -40 -25 40 25, separation 5 m, clearance 5 m; the top at 3.0 m
      EXPECT_GE(p[i].x(), -40.0);
      EXPECT_LE(p[i].x(), 40.0);
      EXPECT_GE(p[i].y(), -25.0);
      EXPECT_LE(p[i].y(), 25.0);
      EXPECT_NEAR(p[i].z() + set.balloons->balloons()[i].radius_m, 3.0, kPosTol_m);
      for (size_t j = 0; j < i; ++j) EXPECT_GE((p[i] - p[j]).head<2>().norm(), 5.0);
      for (size_t v = 0; v < sim->vehicle_count(); ++v) {
        EXPECT_GE((p[i] - sim->truth(v).position_enu_m).head<2>().norm(), 5.0);
      }
    }
    // the bodies are where the state says, after a step
    sim->step();
    for (size_t i = 0; i < p.size(); ++i) {
      const int body = sim->world().body_id(set.balloons->balloons()[i].name);
      EXPECT_LT((physics::body_position_enu_m(sim->world(), body) - (p[i] - Eigen::Vector3d(0, 0, 2.7)))
                    .norm(), 1e-9);
    }
  }
}

// one quad and one balloon at (6, lateral_m); the quad is driven east at 2 m/s at the balloon's centre
// height (2.7 m) from x = 2 to x = 10
std::unique_ptr<sim::Simulation> fly_past(const std::string& label, double lateral_m, double height_m,
                                          ObjectSet* set) {
  auto sim = make_world(label, R"(<uavsim_vehicle type="quad" name="uav0" pos="0 0 0"/>
                                  <uavsim_object type="balloon" name="b0" pos="6 )" +
                                   std::to_string(lateral_m) + R"( 0"/>)");
  *set = add_world_objects(*sim);
  const Eigen::Vector3d v(2.0, 0.0, 0.0);
  for (int k = 0; k <= 4000; ++k) {
    drive_step(*sim, Eigen::Vector3d(2.0 + 0.002 * k, 0.0, height_m), v);
    if (sim->runtime(0).crashed) break;
  }
  return sim;
}

TEST(Balloons, BladesPopABalloonWithoutCrashing) {
  ObjectSet set;
  auto sim = fly_past("pop", 0.0, 2.7, &set);
  ASSERT_EQ(sim->events().count(sim::EventType::kBalloonPopped), 1u);
  EXPECT_EQ(sim->events().count(sim::EventType::kCrash), 0u);
  const BalloonState& b = set.balloons->balloons()[0];
  EXPECT_TRUE(b.popped);
  EXPECT_EQ(b.popped_by, 0);
  // blade tips 0.46 m ahead of the body: contact when the body is at 6 - 0.3 - 0.46 = 5.24 m, 1.62 s
  // after the start at 2 m (at 2 m/s)
  EXPECT_NEAR(b.popped_time_s, (6.0 - 0.3 - 0.46 - 2.0) / 2.0, kPopTimeTol_s);
  const sim::Event& e = sim->events().recent().back();
  EXPECT_EQ(e.type, sim::EventType::kBalloonPopped);
  EXPECT_NE(e.detail.find("b0"), std::string::npos);
  // the quad flew on through where the balloon was
  EXPECT_GT(sim->truth(0).position_enu_m.x(), 9.9);
}

TEST(Balloons, PassingOneMetreAwayPopsNothing) {
  ObjectSet set;
  auto sim = fly_past("miss", 1.0, 2.7, &set);
  EXPECT_EQ(sim->events().count(sim::EventType::kBalloonPopped), 0u);
  EXPECT_EQ(sim->events().count(sim::EventType::kCrash), 0u);
  EXPECT_FALSE(set.balloons->balloons()[0].popped);
}

TEST(Balloons, HittingThePoleIsACrash) {
  ObjectSet set;
  auto sim = fly_past("pole", 0.0, 1.5, &set);
  EXPECT_EQ(sim->events().count(sim::EventType::kBalloonPopped), 0u);
  EXPECT_EQ(sim->events().count(sim::EventType::kCrash), 1u);
  EXPECT_TRUE(sim->runtime(0).crashed);
}

TEST(Balloons, ResetRestoresPoppedBalloons) {
  ObjectSet set;
  auto sim = fly_past("pop_reset", 0.0, 2.7, &set);
  ASSERT_TRUE(set.balloons->balloons()[0].popped);
  sim->reset(1);
  EXPECT_FALSE(set.balloons->balloons()[0].popped);
  EXPECT_EQ(set.balloons->popped_count(), 0u);
  // and it pops again
  for (int k = 0; k <= 4000; ++k) drive_step(*sim, Eigen::Vector3d(2.0 + 0.002 * k, 0.0, 2.7), {2, 0, 0});
  EXPECT_EQ(set.balloons->popped_count(), 1u);
}

}  // namespace
}  // namespace uavsim::server::objects
