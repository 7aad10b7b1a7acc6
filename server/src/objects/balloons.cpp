#include "objects/balloons.hpp"

#include <cmath>

#include "uavsim/common/angles.hpp"
#include "uavsim/common/splitmix.hpp"

namespace uavsim::server::objects {

namespace {

// splitmix64 (Steele, Lea, Flood 2014): a small, fully specified generator, so placements are the same
// on every platform and standard library
struct SplitMix64 {
  uint64_t state;
  uint64_t next() { return common::splitmix64_mix(state += common::kSplitMixGamma); }
  double uniform(double lo, double hi) {  // 53 random bits in [lo, hi)
    return lo + (hi - lo) * static_cast<double>(next() >> 11) * 0x1.0p-53;
  }
};

constexpr uint64_t kBalloonStream = 0xBA11000Full;  // keeps balloon draws apart from sensor noise
constexpr uint64_t kHeightStream = 0xBA110011ull;   // heights apart from positions

// sway: a 0.3 m balloon (Cd 0.47, A = pi 0.3^2) with its entrained air (m_eff ~ 0.1 kg) on a pole whose
// stiffness leans the top 0.25 m in 5 m/s: F = 0.5 * 1.2 * 0.47 * 0.283 * 25 = 2.0 N, torque 2.0 * 2.7 =
// 5.4 N m at 0.25 / 2.7 = 0.093 rad: k = 58 N m/rad; natural frequency sqrt(k / (m h^2)) = 8.9 rad/s
constexpr double kAirDensity_kg_m3 = 1.2;
constexpr double kBalloonCd = 0.47;
constexpr double kBalloonMass_kg = 0.1;
constexpr double kPoleStiffness_nm_rad = 58.0;
constexpr double kPoleDamping_nms_rad = 1.0;  // structural, besides the aerodynamic damping
constexpr int kMaxTries = 10000;

}  // namespace

BalloonField::BalloonField(sim::Simulation& sim, const std::vector<std::string>& names,
                           std::optional<BalloonArena> arena, const sim::BalloonVariation& variation)
    : variation_(variation), world_(sim.world()), arena_(arena) {
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
  SplitMix64 height_rng{seed ^ kHeightStream};
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
    Binding& b = bindings_[i];
    b.lift_m = 0.0;
    if (variation_.height_spread_m > 0) {
      b.lift_m = height_rng.uniform(-variation_.height_spread_m, variation_.height_spread_m);
    }
    b.foot_enu_m = base;
    b.lean_rad.setZero();
    b.lean_rate_rad_s.setZero();
    pose(i);
  }
}

void BalloonField::pose(size_t i) {
  // the body tilted about the pole's foot, raised by its height variation
  const Binding& b = bindings_[i];
  const Eigen::Vector3d lift(0.0, 0.0, b.lift_m);
  Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
  const double lean = b.lean_rad.norm();
  if (lean > 0) q = Eigen::AngleAxisd(lean, Eigen::Vector3d(-b.lean_rad.y(), b.lean_rad.x(), 0.0) / lean);
  state_[i].position_enu_m = b.foot_enu_m + q * (lift + b.centre_in_body_m);
  physics::set_mocap_pose(world_, b.body_id, b.foot_enu_m + q * lift, q);
}

void BalloonField::before_step(sim::Simulation& sim) {
  if (!variation_.sway) return;
  // each pole a damped spring about its foot, driven by the drag on the balloon (header)
  const double dt_s = sim.physics_dt_s();
  const Eigen::Vector2d wind = sim.wind().velocity_enu_m_s().head<2>();
  for (size_t i = 0; i < bindings_.size(); ++i) {
    Binding& b = bindings_[i];
    if (state_[i].popped && b.lean_rad.isZero() && b.lean_rate_rad_s.isZero()) continue;
    const double h_m = b.centre_in_body_m.z() + b.lift_m;
    const double area_m2 = common::kPi * state_[i].radius_m * state_[i].radius_m;
    const double inertia = kBalloonMass_kg * h_m * h_m;
    // a popped balloon no longer catches the wind
    Eigen::Vector2d force_n = Eigen::Vector2d::Zero();
    if (!state_[i].popped) {
      const Eigen::Vector2d rel = wind - h_m * b.lean_rate_rad_s;
      force_n = 0.5 * kAirDensity_kg_m3 * kBalloonCd * area_m2 * rel.norm() * rel;
    }
    const Eigen::Vector2d accel =
        (h_m * force_n - kPoleStiffness_nm_rad * b.lean_rad - kPoleDamping_nms_rad * b.lean_rate_rad_s) / inertia;
    // semi-implicit Euler (stable at the 1 kHz physics step: omega dt ~ 0.01)
    b.lean_rate_rad_s += accel * dt_s;
    b.lean_rad += b.lean_rate_rad_s * dt_s;
    pose(i);
  }
}

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
