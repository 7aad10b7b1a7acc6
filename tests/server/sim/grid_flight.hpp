// A grid world on the ground: a set of its quads arm, take off and hover while the others stay
// parked (tests/server/sim/parking_test.cpp with 100 quads, scale_scenario_test.cpp with
// grid1000.xml).
#pragma once

#include <gtest/gtest.h>

#include <cstdint>
#include <fstream>
#include <string>

#include "physics/world.hpp"
#include "sim/simulation.hpp"
#include "sim_fixture.hpp"

namespace uavsim::server::sim::testing {

// the flyers' hover height after 15 s
inline constexpr double kGridHoverAltTol_m = 0.3;

// Loads world_path (n quads on the ground), checks they all start parked, and has every (n /
// flyers)-th one take off to 5 m and hover for 15 s of sim time while the others stay parked; no
// crash, no constraint buffer overflow.
inline void fly_some_of_a_grid(const std::string& world_path, size_t n, size_t flyers) {
  physics::ComposeOptions o;
  o.models_dir = UAVSIM_MODELS_DIR;
  Simulation sim(physics::World::load(world_path, o), SimConfig{});
  ASSERT_EQ(sim.vehicle_count(), n);
  EXPECT_EQ(sim.world().parked_count(), n);
  wait_ready(sim);
  const size_t stride = n / flyers;
  for (size_t i = 0; i < n; i += stride) {
    sim.post(i, [](fc::FlightController& f) {
      f.set_mode(fc::Mode::kGuided);
      f.arm(false);
      f.takeoff(5.0);
    });
  }
  sim.run_until(sim.time_s() + 15.0);
  for (size_t i = 0; i < n; ++i) {
    const fc::TruthState t = sim.truth(i);
    if (i % stride == 0) {
      // hovering 5 m above the start (the body origin stands 0.16 m up on the gear)
      EXPECT_NEAR(t.position_enu_m.z(), 5.16, kGridHoverAltTol_m) << sim.vehicle_name(i);
      EXPECT_LT(t.velocity_enu_m_s.norm(), 0.3) << sim.vehicle_name(i);
    } else {
      EXPECT_TRUE(sim.world().parked(i)) << sim.vehicle_name(i);
    }
  }
  EXPECT_EQ(sim.events().count(EventType::kCrash), 0u);
  EXPECT_EQ(sim.world().buffer_overflows(), 0);
}

// Writes a world of rows x cols lean quads on the ground, 4 m apart, and returns its path.
inline std::string grid_world(int rows, int cols) {
  const std::string path = ::testing::TempDir() + "/shard_grid_" + std::to_string(rows) + "x" +
                           std::to_string(cols) + ".xml";
  std::ofstream(path) << R"(<mujoco><compiler angle="radian"/><option timestep="0.001"/>
    <include file=")" << UAVSIM_MODELS_DIR << R"(/common/ground.xml"/><worldbody>
    <uavsim_grid type="quad" prefix="uav" rows=")" << rows << R"(" cols=")" << cols
                      << R"(" spacing="4" collision="lean"/></worldbody></mujoco>)";
  return path;
}

// Simulation::state_hash() (time, qpos, qvel) and, for every vehicle, its flight controller's estimate,
// mode and arming, its motor commands, rotor speeds and thrusts and its battery, then every event (time,
// type, vehicle, detail): equal for two runs only if the autopilots did bit for bit the same.
inline uint64_t vehicles_hash(Simulation& sim) {
  uint64_t h = sim.state_hash();
  auto mix = [&h](const void* data, size_t n) {
    const auto* p = static_cast<const unsigned char*>(data);
    for (size_t i = 0; i < n; ++i) {
      h ^= p[i];
      h *= 0x100000001B3ull;
    }
  };
  for (size_t i = 0; i < sim.vehicle_count(); ++i) {
    const fc::EstimatedState& e = sim.fc(i).estimate();
    mix(e.position_enu_m.data(), 3 * sizeof(double));
    mix(e.velocity_enu_m_s.data(), 3 * sizeof(double));
    mix(e.q_enu_body.coeffs().data(), 4 * sizeof(double));
    const int mode_armed[2] = {static_cast<int>(sim.fc(i).mode()), sim.fc(i).armed() ? 1 : 0};
    mix(mode_armed, sizeof(mode_armed));
    const VehicleRuntime& v = sim.runtime(i);
    mix(v.motor_cmd.data(), v.motor_cmd.size() * sizeof(double));
    mix(v.motors.speed.data(), v.motors.speed.size() * sizeof(double));
    mix(v.thrust_n.data(), v.thrust_n.size() * sizeof(double));
    const double battery[3] = {v.battery.consumed_mah, v.battery.current_a, v.battery.voltage_v};
    mix(battery, sizeof(battery));
  }
  for (const Event& e : sim.events().recent()) {
    mix(&e.time_s, sizeof(e.time_s));
    const int type_vehicle[2] = {static_cast<int>(e.type), e.vehicle};
    mix(type_vehicle, sizeof(type_vehicle));
    mix(e.detail.data(), e.detail.size());
  }
  return h;
}

// Loads world_path (a grid of quads on the ground) in `shards` physics shards stepped by `threads`
// threads, has every vehicle take off to 5 m (in waves of `wave` vehicles, 0.5 s apart: each wave's
// vehicles are awake on their gear at once) and runs until sim time end_s. Checks that every vehicle
// hovers 5 m up with no crash and no buffer overflow, and returns vehicles_hash().
inline uint64_t fly_all_of_a_sharded_grid(const std::string& world_path, size_t n, int shards, int threads,
                                          size_t wave, double end_s) {
  physics::ComposeOptions o;
  o.models_dir = UAVSIM_MODELS_DIR;
  Simulation sim(physics::World::load(world_path, o, physics::ShardOptions{shards, threads}), SimConfig{});
  EXPECT_EQ(sim.world().shard_count(), shards);
  EXPECT_EQ(sim.world().thread_count(), threads);
  EXPECT_EQ(sim.vehicle_count(), n);
  EXPECT_EQ(sim.world().parked_count(), n);
  wait_ready(sim);
  for (size_t first = 0; first < n; first += wave) {
    for (size_t i = first; i < std::min(n, first + wave); ++i) {
      sim.post(i, [](fc::FlightController& f) {
        f.set_mode(fc::Mode::kGuided);
        f.arm(false);
        f.takeoff(5.0);
      });
    }
    sim.run_until(sim.time_s() + 0.5);
  }
  sim.run_until(end_s);
  for (size_t i = 0; i < n; ++i) {
    const fc::TruthState t = sim.truth(i);
    // hovering 5 m above the start (the body origin stands 0.16 m up on the gear)
    EXPECT_NEAR(t.position_enu_m.z(), 5.16, kGridHoverAltTol_m) << sim.vehicle_name(i);
    EXPECT_FALSE(sim.world().parked(i)) << sim.vehicle_name(i);
  }
  EXPECT_EQ(sim.events().count(EventType::kCrash), 0u);
  EXPECT_EQ(sim.world().buffer_overflows(), 0);
  return vehicles_hash(sim);
}

}  // namespace uavsim::server::sim::testing
