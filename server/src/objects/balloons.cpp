#include "objects/balloons.hpp"

#include <cmath>

namespace uavsim::server::objects {

namespace {

// splitmix64 (Steele, Lea, Flood 2014): a small, fully specified generator, so placements are the same
// on every platform and standard library
struct SplitMix64 {
  uint64_t state;
  uint64_t next() {
    uint64_t z = (state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  double uniform(double lo, double hi) {  // 53 random bits in [lo, hi)
    return lo + (hi - lo) * static_cast<double>(next() >> 11) * 0x1.0p-53;
  }
};

constexpr uint64_t kBalloonStream = 0xBA11000Full;  // keeps balloon draws apart from sensor noise
constexpr int kMaxTries = 10000;

}  // namespace

BalloonField::BalloonField(sim::Simulation& sim, const std::vector<std::string>& names,
                           std::optional<BalloonArena> arena)
    : world_(sim.world()), arena_(arena) {
  for (const std::string& name : names) {
    Binding b;
    b.body_id = world_.body_id(name);
    if (b.body_id < 0 || physics::mocap_index(world_, b.body_id) < 0) {
      throw physics::WorldError("balloon '" + name + "': no mocap body of that name (models/objects/balloon.xml)");
    }
    int sphere = -1;
    for (int g : physics::body_geoms(world_, b.body_id)) {
      if (physics::geom_local_name(world_, g) == "balloon") sphere = g;
    }
    if (sphere < 0) throw physics::WorldError("balloon '" + name + "': no geom named '" + name + "/balloon'");
    b.sphere = physics::geom_switch(world_, sphere);
    b.centre_in_body_m = physics::geom_position_in_body_m(world_, sphere);
    b.initial_pos_enu_m = physics::body_position_enu_m(world_, b.body_id);
    bindings_.push_back(b);
    BalloonState s;
    s.name = name;
    s.radius_m = physics::geom_radius_m(world_, sphere);
    state_.push_back(s);
  }
  for (size_t i = 0; i < sim.vehicle_count(); ++i) {
    vehicle_starts_.push_back(sim.truth(i).position_enu_m.head<2>());
  }
  reset(sim.config().seed);
}

void BalloonField::place(uint64_t seed) {
  SplitMix64 rng{seed ^ kBalloonStream};
  std::vector<Eigen::Vector2d> placed;
  for (size_t i = 0; i < bindings_.size(); ++i) {
    Eigen::Vector3d base = bindings_[i].initial_pos_enu_m;
    if (arena_) {
      // rejection sampling: uniform in the rectangle, away from other balloons and the vehicles
      Eigen::Vector2d xy;
      for (int attempt = 0; attempt < kMaxTries; ++attempt) {
        xy = Eigen::Vector2d(rng.uniform(arena_->min_enu_m.x(), arena_->max_enu_m.x()),
                             rng.uniform(arena_->min_enu_m.y(), arena_->max_enu_m.y()));
        bool ok = true;
        for (const auto& p : placed) ok = ok && (p - xy).norm() >= arena_->min_separation_m;
        for (const auto& p : vehicle_starts_) ok = ok && (p - xy).norm() >= arena_->clearance_m;
        if (ok) break;
      }
      placed.push_back(xy);
      base = Eigen::Vector3d(xy.x(), xy.y(), 0.0);
    }
    state_[i].position_enu_m = base + bindings_[i].centre_in_body_m;
    physics::set_mocap_pose(world_, bindings_[i].body_id, base, Eigen::Quaterniond::Identity());
  }
}

void BalloonField::before_step(sim::Simulation& /*sim*/) {}

bool BalloonField::on_contact(sim::Simulation& sim, const physics::VehicleContact& contact) {
  for (size_t i = 0; i < bindings_.size(); ++i) {
    if (bindings_[i].body_id != contact.other_body) continue;
    if (contact.other_geom != bindings_[i].sphere.geom) return false;  // the pole: default (crash)
    BalloonState& s = state_[i];
    if (s.popped) return true;  // other contacts of the step it popped in
    if (physics::geom_local_name(world_, contact.geom).rfind("blade", 0) != 0) return false;
    s.popped = true;
    s.popped_by = contact.vehicle;
    s.popped_time_s = sim.time_s();
    physics::set_geom_enabled(world_, bindings_[i].sphere, false);
    sim.record(sim::EventType::kBalloonPopped, contact.vehicle,
               s.name + " by " + physics::geom_local_name(world_, contact.geom));
    return true;
  }
  return false;
}

void BalloonField::reset(uint64_t seed) {
  for (size_t i = 0; i < bindings_.size(); ++i) {
    physics::set_geom_enabled(world_, bindings_[i].sphere, true);
    state_[i].popped = false;
    state_[i].popped_by = -1;
    state_[i].popped_time_s = 0.0;
  }
  place(seed);
}

size_t BalloonField::popped_count() const {
  size_t n = 0;
  for (const auto& s : state_) n += s.popped ? 1 : 0;
  return n;
}

}  // namespace uavsim::server::objects
