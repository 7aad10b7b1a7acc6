// Helpers for world-object tests: worlds written inline (composed from a temporary file, so that
// <uavsim_vehicle>/<uavsim_object> work) and a kinematically driven vehicle.
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <memory>
#include <string>

#include "objects/world_objects.hpp"
#include "physics/object_bodies.hpp"
#include "physics/world.hpp"
#include "sim/simulation.hpp"

namespace uavsim::server::objects::testing {

// Writes body (the inside of <worldbody>) and custom (the inside of <custom>) as a world on flat ground
// and loads it.
inline std::unique_ptr<sim::Simulation> make_world(const std::string& label, const std::string& body,
                                                   const std::string& custom = "", uint64_t seed = 1) {
  const std::string path = ::testing::TempDir() + "/uavsim_objects_" + label + ".xml";
  std::ofstream(path) << "<mujoco model=\"" << label << "\">\n"
                      << "  <compiler angle=\"radian\"/>\n"
                      << "  <option timestep=\"0.001\" integrator=\"Euler\"/>\n"
                      << "  <include file=\"" << UAVSIM_MODELS_DIR << "/common/ground.xml\"/>\n"
                      << "  <worldbody>\n" << body << "\n  </worldbody>\n"
                      << (custom.empty() ? "" : "  <custom>\n" + custom + "\n  </custom>\n")
                      << "</mujoco>\n";
  physics::ComposeOptions o;
  o.models_dir = UAVSIM_MODELS_DIR;
  sim::SimConfig c;
  c.seed = seed;
  return std::make_unique<sim::Simulation>(physics::World::load(path, o), c);
}

inline std::unique_ptr<sim::Simulation> make_shipped(const std::string& world, uint64_t seed = 1) {
  physics::ComposeOptions o;
  o.models_dir = UAVSIM_MODELS_DIR;
  sim::SimConfig c;
  c.seed = seed;
  return std::make_unique<sim::Simulation>(
      physics::World::load(std::string(UAVSIM_MODELS_DIR) + "/worlds/" + world, o), c);
}

// Moves vehicle 0 kinematically (level, facing east) to p at velocity v, then steps once.
inline void drive_step(sim::Simulation& sim, const Eigen::Vector3d& p, const Eigen::Vector3d& v,
                       size_t vehicle = 0) {
  physics::set_vehicle_state(sim.world(), vehicle, p, Eigen::Quaterniond::Identity(), v,
                             Eigen::Vector3d::Zero());
  sim.step();
}

// GUIDED (retried every 0.5 s until the estimator has converged), arm, take off to altitude_m and run
// until within 0.3 m of it; false after 40 s of sim time.
inline bool take_off(sim::Simulation& sim, double altitude_m, size_t vehicle = 0) {
  fc::CommandResult result = fc::CommandResult::kFailed;
  while (result != fc::CommandResult::kAccepted && sim.time_s() < 30.0) {
    sim.post(vehicle, [&](fc::FlightController& f) {
      result = f.set_mode(fc::Mode::kGuided);
      if (result == fc::CommandResult::kAccepted) result = f.arm(false);
      if (result == fc::CommandResult::kAccepted) result = f.takeoff(altitude_m);
    });
    sim.run_until(sim.time_s() + 0.5);
  }
  while (std::abs(sim.truth(vehicle).position_enu_m.z() - altitude_m) > 0.3 && sim.time_s() < 40.0) sim.step();
  return std::abs(sim.truth(vehicle).position_enu_m.z() - altitude_m) <= 0.3;
}

}  // namespace uavsim::server::objects::testing
