#include "objects/truck.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>

#include "physics/object_bodies.hpp"

namespace uavsim::server::objects {

namespace {
constexpr double kGravity_m_s2 = 9.81;
// rotor lift above this share of the weight releases a carried vehicle (a deliberate climb, not the
// landing controller's last flare)
constexpr double kReleaseLiftRatio = 1.2;
}  // namespace

Truck::Truck(sim::Simulation& sim, const TruckParams& params) : params_(params), track_(params.track) {
  physics::World& world = sim.world();
  body_id_ = world.body_id(params_.name);
  if (body_id_ < 0 || physics::mocap_index(world, body_id_) < 0) {
    throw physics::WorldError("truck '" + params_.name + "': the world needs a mocap body named '" +
                              params_.name + "' (models/objects/truck.xml)");
  }
  // the deck: geoms whose local name starts with "deck"; its top is the highest of them
  double top = -1e9;
  for (int g : physics::body_geoms(world, body_id_)) {
    if (physics::geom_local_name(world, g).rfind("deck", 0) != 0) continue;
    deck_geoms_.push_back(g);
    top = std::max(top, physics::box_top_in_body_m(world, g));
  }
  if (deck_geoms_.empty()) {
    throw physics::WorldError("truck '" + params_.name + "': body has no geom named '" + params_.name +
                              "/deck' (models/objects/truck.xml)");
  }
  deck_top_m_ = top;
  reset(sim.config().seed);
  before_step(sim);
}

void Truck::pose_at(double time_s, Eigen::Vector3d* p, Eigen::Quaterniond* q, Eigen::Vector3d* v,
                    double* yaw_rate_rad_s) const {
  // the ideal point the driver follows, and the driver's offset to the left of it
  const double speed = driver_.speed_m_s(params_.speed, time_s);
  const TrackPoint tp = track_.at(driver_.arc_length_m(params_.speed, time_s));
  const Eigen::Vector2d normal(-tp.tangent_enu.y(), tp.tangent_enu.x());
  const double l = driver_.lateral_m(time_s);
  const double l_rate = driver_.lateral_rate_m_s(time_s);
  const Eigen::Vector2d xy = tp.position_enu_m + l * normal;
  // d/dt (c(s) + l n(s)) = s' (1 - kappa l) t + l' n (Frenet: dn/ds = -kappa t)
  const double along = speed * (1.0 - tp.curvature_1_m * l);
  const Eigen::Vector2d vxy = along * tp.tangent_enu + l_rate * normal;
  // the truck points where it goes: the track's heading turned by the steering angle atan(l' / along)
  const double steer = std::atan2(l_rate, along);
  *p = Eigen::Vector3d(xy.x(), xy.y(), 0.0);
  *q = Eigen::Quaterniond(Eigen::AngleAxisd(tp.heading_rad() + steer, Eigen::Vector3d::UnitZ()));
  *v = Eigen::Vector3d(vxy.x(), vxy.y(), 0.0);
  // yaw rate = speed x signed curvature, plus the steering angle's rate (central difference: it is
  // smooth and small, below l'' / speed)
  double steer_rate = 0.0;
  if (driver_.enabled()) {
    constexpr double kH_s = 1e-3;
    auto steer_at = [&](double t) {
      const TrackPoint a = track_.at(driver_.arc_length_m(params_.speed, t));
      return std::atan2(driver_.lateral_rate_m_s(t),
                        driver_.speed_m_s(params_.speed, t) * (1.0 - a.curvature_1_m * driver_.lateral_m(t)));
    };
    steer_rate = (steer_at(time_s + kH_s) - steer_at(time_s - kH_s)) / (2.0 * kH_s);
  }
  *yaw_rate_rad_s = speed * tp.curvature_1_m + steer_rate;
}

void Truck::before_step(sim::Simulation& sim) {
  physics::World& world = sim.world();
  Eigen::Vector3d p, v;
  Eigen::Quaterniond q;
  double yaw_rate = 0.0;
  pose_at(sim.time_s(), &p, &q, &v, &yaw_rate);
  physics::set_mocap_pose(world, body_id_, p, q);

  // carry landed vehicles; let go of those whose rotors lift more than their weight
  const Eigen::Vector3d omega_enu(0.0, 0.0, yaw_rate);
  for (auto it = carried_.begin(); it != carried_.end();) {
    const auto vehicle = static_cast<size_t>(it->vehicle);
    const std::vector<double>& thrust = sim.runtime(vehicle).thrust_n;
    const double lift_n = std::accumulate(thrust.begin(), thrust.end(), 0.0);
    if (lift_n > kReleaseLiftRatio * sim.airframe(vehicle).mass_kg * kGravity_m_s2) {
      it = carried_.erase(it);
      continue;
    }
    const Eigen::Vector3d r_enu = q * it->p_truck_m;
    const Eigen::Quaterniond q_body = q * it->q_truck_body;
    // a point fixed to the truck moves at v + omega x r; the body turns at the truck's yaw rate
    physics::set_vehicle_state(world, vehicle, p + r_enu, q_body, v + omega_enu.cross(r_enu),
                               q_body.conjugate() * omega_enu);
    ++it;
  }
}

bool Truck::on_contact(sim::Simulation& sim, const physics::VehicleContact& contact) {
  if (contact.other_body != body_id_) return false;
  if (std::find(deck_geoms_.begin(), deck_geoms_.end(), contact.other_geom) == deck_geoms_.end()) {
    return false;  // the cab, the wheels: the default rules (a crash)
  }
  if (!contact.landing_gear) return false;
  const auto carried = std::find_if(carried_.begin(), carried_.end(),
                                    [&](const Carried& c) { return c.vehicle == contact.vehicle; });
  if (carried != carried_.end()) return true;

  // relative speed of the vehicle against the deck point under it
  physics::World& world = sim.world();
  Eigen::Vector3d p, v;
  Eigen::Quaterniond q;
  double yaw_rate = 0.0;
  pose_at(sim.time_s(), &p, &q, &v, &yaw_rate);
  const fc::TruthState t = world.truth(static_cast<size_t>(contact.vehicle));
  const Eigen::Vector3d r = t.position_enu_m - p;
  const Eigen::Vector3d v_deck = v + Eigen::Vector3d(0.0, 0.0, yaw_rate).cross(r);
  const double relative = (t.velocity_enu_m_s - v_deck).norm();
  if (relative < params_.landing_speed_m_s && !sim.runtime(static_cast<size_t>(contact.vehicle)).crashed) {
    Carried c;
    c.vehicle = contact.vehicle;
    c.p_truck_m = q.conjugate() * r;
    c.q_truck_body = q.conjugate() * t.q_enu_body;
    carried_.push_back(c);
    char detail[160];
    std::snprintf(detail, sizeof(detail), "%s: relative speed %.2f m/s, %.2f m from the marker centre",
                  params_.name.c_str(), relative,
                  Eigen::Vector2d(c.p_truck_m.x(), c.p_truck_m.y()).norm());
    sim.record(sim::EventType::kLandedOnTarget, contact.vehicle, detail);
  }
  return true;  // touching the deck is never a crash
}

void Truck::reset(uint64_t seed) {
  carried_.clear();
  driver_ = TruckDriver(params_.driver, seed, params_.name);
}

TruckState Truck::state(double time_s) const {
  TruckState s;
  s.name = params_.name;
  const double unwrapped = driver_.arc_length_m(params_.speed, time_s);
  s.laps = static_cast<int>(std::floor(unwrapped / track_.length_m()));
  s.s_m = unwrapped - s.laps * track_.length_m();
  Eigen::Quaterniond q;
  double yaw_rate = 0.0;
  pose_at(time_s, &s.position_enu_m, &q, &s.velocity_enu_m_s, &yaw_rate);
  s.speed_m_s = s.velocity_enu_m_s.norm();
  s.yaw_rad = std::remainder(2.0 * std::atan2(q.z(), q.w()), 4.0 * std::acos(0.0));
  s.deck_centre_enu_m = s.position_enu_m + Eigen::Vector3d(0.0, 0.0, deck_top_m_);
  for (const Carried& c : carried_) s.carried_vehicles.push_back(c.vehicle);
  return s;
}

}  // namespace uavsim::server::objects
