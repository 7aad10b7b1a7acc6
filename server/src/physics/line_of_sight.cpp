#include "physics/line_of_sight.hpp"

#include <mujoco/mujoco.h>

#include <algorithm>

namespace uavsim::server::physics {

namespace {

// a segment crosses at most a handful of geoms before it ends; each hit restarts past it
constexpr int kMaxHits = 32;
// how far past a hit the next cast starts (m): far below any geom, far above rounding
constexpr double kStepPast_m = 1e-4;

// the root body of a vehicle in shard 0's model (-1: the vehicle lives in another shard, or the
// index is no vehicle)
int vehicle_root(const World& world, size_t vehicle) {
  if (vehicle >= world.vehicles().size()) return -1;
  const VehicleBinding& v = world.vehicles()[vehicle];
  if (v.shard != 0 || v.body_id < 0) return -1;
  return world.model()->body_rootid[v.body_id];
}

}  // namespace

double LineOfSight::blocked_loss_db(const Eigen::Vector3d& a_enu_m, const Eigen::Vector3d& b_enu_m,
                                    size_t vehicle_a, size_t vehicle_b,
                                    const std::array<double, kGeomGroupCount>& loss_db) const {
  // only the groups that block are cast against
  mjtByte groups[kGeomGroupCount];
  bool any = false;
  for (size_t g = 0; g < kGeomGroupCount; ++g) {
    groups[g] = loss_db[g] > 0.0 ? 1 : 0;
    any = any || groups[g];
  }
  const double length_m = (b_enu_m - a_enu_m).norm();
  if (!any || length_m <= 0.0) return 0.0;
  const mjModel* m = world_.model();
  const mjData* d = world_.data();
  const int root_a = vehicle_root(world_, vehicle_a);
  const int root_b = vehicle_root(world_, vehicle_b);
  const int body_a = root_a >= 0 ? world_.vehicles()[vehicle_a].body_id : -1;
  const Eigen::Vector3d dir = (b_enu_m - a_enu_m) / length_m;
  double loss = 0.0;
  double from_m = 0.0;  // distance along the segment the next cast starts at
  for (int k = 0; k < kMaxHits && from_m < length_m; ++k) {
    const Eigen::Vector3d p = a_enu_m + from_m * dir;
    const mjtNum pnt[3] = {p.x(), p.y(), p.z()};
    const mjtNum vec[3] = {dir.x(), dir.y(), dir.z()};
    int geom = -1;
    const mjtNum x = mj_ray(m, d, pnt, vec, groups, 1, body_a, &geom);
    if (x < 0.0 || geom < 0 || from_m + x >= length_m) break;
    const int root = m->body_rootid[m->geom_bodyid[geom]];
    // the receiver's own geoms end the path; the sender's other parts (rotors) do not block
    if (root == root_b && root_b >= 0) break;
    // a vehicle blocks with the parts it collides with (hull, gear), not with the ones only drawn
    // (arms, rotors): the same answer whether or not its world carries them (world_composer.hpp)
    if ((root != root_a || root_a < 0) && !world_.vehicle_visual_only(geom)) {
      const int g = m->geom_group[geom];
      if (g >= 0 && g < static_cast<int>(kGeomGroupCount)) loss = std::max(loss, loss_db[g]);
    }
    from_m += x + kStepPast_m;
  }
  return loss;
}

}  // namespace uavsim::server::physics
