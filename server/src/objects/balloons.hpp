// MBZIRC 2020 Challenge 1 balloons (seed 7.2): green balloons on poles, top ~3 m above the ground, popped
// by a vehicle's blade geoms (geoms whose local name starts with "blade"). A pop records balloon_popped
// and switches the balloon's sphere off (no collisions, invisible); it is not a crash. Any other vehicle
// contact with a balloon or its pole is left to the default rules (a crash).
//
// World file: each balloon is an object instance (models/objects/balloon.xml, a mocap body):
//   <uavsim_object type="balloon" name="b0" pos="10 5 0"/>
// With the world numeric
//   <numeric name="uavsim:balloon_arena" data="x_min y_min x_max y_max [min_separation_m] [clearance_m]"/>
// every balloon is placed at a seeded random position in that rectangle at start and on each
// reset(seed), at least min_separation_m (default 5) from the other balloons and clearance_m (default 5)
// from every vehicle's start position; without it balloons stay where the world put them.
//
// Field conditions (sim::BalloonVariation): each balloon's height is drawn per seed, uniform in the
// nominal +- height_spread_m (the body moves up or down; the pole reaches 0.6 m below its foot, so it
// still meets the ground), and with sway the balloons lean and sway in the wind: each pole is a stiff
// spring about its foot, loaded by the balloon's quadratic drag on the air-relative velocity,
//   I th'' = h F(w - h th') - k th - c th',  F(v) = 1/2 rho Cd A |v| v,  I = m_eff h^2,
// with constants that give a 0.25 m lean at the top in a 5 m/s wind (balloons.cpp).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "physics/object_bodies.hpp"
#include "sim/simulation.hpp"

namespace uavsim::server::objects {

struct BalloonArena {
  Eigen::Vector2d min_enu_m = Eigen::Vector2d(-45.0, -30.0);
  Eigen::Vector2d max_enu_m = Eigen::Vector2d(45.0, 30.0);
  double min_separation_m = 5.0;
  double clearance_m = 5.0;  // from the vehicles' start positions
};

// One balloon's ground truth.
struct BalloonState {
  std::string name;
  Eigen::Vector3d position_enu_m = Eigen::Vector3d::Zero();  // the balloon's centre
  double radius_m = 0.0;
  bool popped = false;
  int popped_by = -1;         // vehicle index
  double popped_time_s = 0.0;
};

class BalloonField : public sim::WorldObject {
 public:
  // Binds to the balloon instances named in names (mocap bodies with a geom NAME/balloon and a pole
  // NAME/pole) and places them. Throws physics::WorldError naming the body that is missing a part.
  BalloonField(sim::Simulation& sim, const std::vector<std::string>& names,
               std::optional<BalloonArena> arena, const sim::BalloonVariation& variation = {});

  void before_step(sim::Simulation& sim) override;  // sway (field conditions); else nothing moves
  bool on_contact(sim::Simulation& sim, const physics::VehicleContact& contact) override;
  // Un-pops every balloon and, with an arena, draws new positions from seed.
  void reset(uint64_t seed) override;

  // All balloons, in world order. Loop thread only.
  const std::vector<BalloonState>& balloons() const { return state_; }
  size_t popped_count() const;

 private:
  struct Binding {
    int body_id = -1;
    physics::GeomSwitch sphere;
    Eigen::Vector3d centre_in_body_m = Eigen::Vector3d::Zero();
    Eigen::Vector3d initial_pos_enu_m = Eigen::Vector3d::Zero();
    Eigen::Vector3d foot_enu_m = Eigen::Vector3d::Zero();  // where the pole meets the ground
    double lift_m = 0.0;                                     // height variation
    Eigen::Vector2d lean_rad = Eigen::Vector2d::Zero();     // sway: tilt towards x, y
    Eigen::Vector2d lean_rate_rad_s = Eigen::Vector2d::Zero();
  };
  void place(uint64_t seed);
  void pose(size_t i);

  sim::BalloonVariation variation_;
  physics::World& world_;
  std::optional<BalloonArena> arena_;
  std::vector<Eigen::Vector2d> vehicle_starts_;
  std::vector<Binding> bindings_;
  std::vector<BalloonState> state_;
};

}  // namespace uavsim::server::objects
