// Line of sight through the MuJoCo world, for the radio (radio/sim_radio.hpp): which geoms the
// straight path between two vehicles' antennas crosses (MuJoCo's mj_ray against the static scene
// and every other body: buildings, poles, trucks, other vehicles), as the extra loss of the path.
// The antenna is the vehicle body's origin; the two vehicles' own geoms never block their path, and
// another vehicle blocks it only with the geoms it collides with (its hull and landing gear, not
// the arms and rotors that are only drawn), so the answer does not depend on whether the world was
// loaded with its vehicles' visual-only geoms (ComposeOptions::vehicle_visual_geoms).
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstddef>

#include "physics/world.hpp"

namespace uavsim::server::physics {

inline constexpr size_t kGeomGroupCount = 6;  // MuJoCo's mjNGROUP

class LineOfSight {
 public:
  explicit LineOfSight(const World& world) : world_(world) {}

  // The largest loss_db[g] among the geom groups g of the geoms the segment from a to b crosses
  // (0: nothing in a group with a loss > 0 is in the way). vehicle_a and vehicle_b index
  // world.vehicles(); an index past them is an end that is no vehicle (the GCS link's ground
  // station), whose own geoms there are none to skip. Reads the last kinematics pass (geom poses of
  // the last step). Loop thread only (the world's data).
  double blocked_loss_db(const Eigen::Vector3d& a_enu_m, const Eigen::Vector3d& b_enu_m,
                         size_t vehicle_a, size_t vehicle_b,
                         const std::array<double, kGeomGroupCount>& loss_db) const;

 private:
  const World& world_;
};

}  // namespace uavsim::server::physics
