// World files the physics tests write: a MuJoCo world with uavsim's ground and the given
// <worldbody> content (vehicles, grids), composed from the source tree's models.
#pragma once

#include <filesystem>
#include <fstream>
#include <string>

#include "physics/world_composer.hpp"

namespace uavsim::server::physics::testing {

// Writes temp/DIR/NAME (timestep 1 ms, angles in radians, the shipped ground) and returns its path.
inline std::string write_world(const std::string& dir, const std::string& name,
                               const std::string& worldbody) {
  const std::filesystem::path d = std::filesystem::temp_directory_path() / dir;
  std::filesystem::create_directories(d);
  const std::filesystem::path p = d / name;
  std::ofstream(p) << "<mujoco>\n  <compiler angle=\"radian\"/>\n  <option timestep=\"0.001\"/>\n"
                   << "  <include file=\"" << UAVSIM_MODELS_DIR << "/common/ground.xml\"/>\n"
                   << "  <worldbody>\n"
                   << worldbody << "\n  </worldbody>\n</mujoco>\n";
  return p.string();
}

// Composing from the source tree's models.
inline ComposeOptions source_models() {
  ComposeOptions o;
  o.models_dir = UAVSIM_MODELS_DIR;
  return o;
}

}  // namespace uavsim::server::physics::testing
