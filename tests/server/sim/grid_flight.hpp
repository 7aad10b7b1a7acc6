// A grid world on the ground: a set of its quads arm, take off and hover while the others stay
// parked (tests/server/sim/parking_test.cpp with 100 quads, scale_scenario_test.cpp with
// grid1000.xml).
#pragma once

#include <gtest/gtest.h>

#include <string>

#include "physics/world.hpp"
#include "sim/simulation.hpp"
#include "sim_fixture.hpp"

namespace uavsim::server::sim::testing {

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
      EXPECT_NEAR(t.position_enu_m.z(), 5.16, 0.3) << sim.vehicle_name(i);
      EXPECT_LT(t.velocity_enu_m_s.norm(), 0.3) << sim.vehicle_name(i);
    } else {
      EXPECT_TRUE(sim.world().parked(i)) << sim.vehicle_name(i);
    }
  }
  EXPECT_EQ(sim.events().count(EventType::kCrash), 0u);
  EXPECT_EQ(sim.world().buffer_overflows(), 0);
}

}  // namespace uavsim::server::sim::testing
