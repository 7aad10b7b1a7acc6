// Shared helpers for tests that fly vehicles in the MuJoCo simulation through the command path.
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <string>

#include "physics/world.hpp"
#include "sim/simulation.hpp"
#include "uavsim/common/angles.hpp"

namespace uavsim::server::sim::testing {

// how near the take-off target take_off waits for, and then requires
inline constexpr double kTakeoffReachedTol_m = 0.3;

inline std::unique_ptr<Simulation> make_sim(const std::string& world, uint64_t seed = 1) {
  physics::ComposeOptions o;
  o.models_dir = UAVSIM_MODELS_DIR;
  SimConfig c;
  c.seed = seed;
  return std::make_unique<Simulation>(
      physics::World::load(std::string(UAVSIM_MODELS_DIR) + "/worlds/" + world, o), c);
}

// runs until the flight controller is ready to arm (GPS fix, estimator settled), at most 20 s
inline void wait_ready(Simulation& sim, size_t vehicle = 0) {
  while (!sim.fc(vehicle).prearm_ok() && sim.time_s() < 20.0) sim.step();
  ASSERT_TRUE(sim.fc(vehicle).prearm_ok()) << "pre-arm checks never passed";
}

// GUIDED, arm and take off to altitude_m above home (where the vehicle stands: its body origin sits
// above the ground by the landing-gear height); runs until within 0.3 m of it (or fails after 30 s)
inline void take_off(Simulation& sim, double altitude_m, size_t vehicle = 0) {
  wait_ready(sim, vehicle);
  const double target_z = sim.truth(vehicle).position_enu_m.z() + altitude_m;
  fc::CommandResult mode = fc::CommandResult::kFailed, arm = mode, takeoff = mode;
  sim.post(vehicle, [&](fc::FlightController& f) {
    mode = f.set_mode(fc::Mode::kGuided);
    arm = f.arm(false);
    takeoff = f.takeoff(altitude_m);
  });
  sim.step();
  sim.step();
  ASSERT_EQ(mode, fc::CommandResult::kAccepted);
  ASSERT_EQ(arm, fc::CommandResult::kAccepted);
  ASSERT_EQ(takeoff, fc::CommandResult::kAccepted);
  const double deadline = sim.time_s() + 30.0;
  while (std::abs(sim.truth(vehicle).position_enu_m.z() - target_z) > kTakeoffReachedTol_m &&
         sim.time_s() < deadline) {
    sim.step();
  }
  ASSERT_NEAR(sim.truth(vehicle).position_enu_m.z(), target_z, kTakeoffReachedTol_m)
      << "take-off did not reach altitude";
}

inline void goto_enu(Simulation& sim, const Eigen::Vector3d& p, size_t vehicle = 0) {
  sim.post(vehicle, [p](fc::FlightController& f) {
    fc::GuidedTarget t;
    t.position_enu_m = p;
    EXPECT_EQ(f.set_guided_target(t), fc::CommandResult::kAccepted);
  });
}

inline double yaw_of(const Eigen::Quaterniond& q) {
  const Eigen::Vector3d x = q * Eigen::Vector3d::UnitX();
  return std::atan2(x.y(), x.x());
}

using common::wrap_pi;  // (-pi, pi]

}  // namespace uavsim::server::sim::testing
