#include "objects/world_objects.hpp"

#include <cmath>
#include <memory>
#include <sstream>

#include "physics/object_bodies.hpp"
#include "uavsim/common/angles.hpp"

namespace uavsim::server::objects {

namespace {

constexpr const char* kObjectPrefix = "uavsim:object:";
constexpr const char* kGimbalPrefix = "uavsim:gimbal:";

// a custom numeric with between 1 and max_size values, all finite; empty if absent
std::vector<double> numeric(const physics::World& world, const std::string& name, size_t max_size) {
  std::vector<double> v = physics::custom_numeric(world, name);
  if (v.size() > max_size) {
    throw physics::WorldError("custom numeric '" + name + "' has " + std::to_string(v.size()) +
                              " values, at most " + std::to_string(max_size) + " expected");
  }
  for (double x : v) {
    if (!std::isfinite(x)) throw physics::WorldError("custom numeric '" + name + "' has a non-finite value");
  }
  return v;
}

TruckParams truck_params(const physics::World& world, const std::string& name) {
  TruckParams p;
  p.name = name;
  // uavsim:NAME:track = circle_radius_m centre_separation_m centre_x_m centre_y_m yaw_deg
  const std::string track_name = "uavsim:" + name + ":track";
  const std::vector<double> t = numeric(world, track_name, 5);
  if (t.size() > 0) p.track.circle_radius_m = t[0];
  if (t.size() > 1) p.track.centre_separation_m = t[1];
  if (t.size() > 2) p.track.centre_enu_m.x() = t[2];
  if (t.size() > 3) p.track.centre_enu_m.y() = t[3];
  if (t.size() > 4) p.track.yaw_rad = t[4] * common::kPi / 180.0;
  if (const std::string e = validate(p.track); !e.empty()) {
    throw physics::WorldError("custom numeric '" + track_name + "': " + e);
  }
  // uavsim:NAME:speed = speed1_kmh speed2_kmh switch_time_s start_s_m
  const std::string speed_name = "uavsim:" + name + ":speed";
  const std::vector<double> s = numeric(world, speed_name, 4);
  if (s.size() > 0) p.speed.speed1_m_s = s[0] / 3.6;
  if (s.size() > 1) p.speed.speed2_m_s = s[1] / 3.6;
  if (s.size() > 2) p.speed.switch_time_s = s[2];
  if (s.size() > 3) p.speed.start_s_m = s[3];
  if (p.speed.speed1_m_s < 0 || p.speed.speed2_m_s < 0 || p.speed.switch_time_s < 0) {
    throw physics::WorldError("custom numeric '" + speed_name + "': speeds and switch time must be >= 0");
  }
  // uavsim:NAME:driver = lateral_amplitude_m speed_wobble_fraction (truck_driver.hpp)
  const std::string driver_name = "uavsim:" + name + ":driver";
  const std::vector<double> d = numeric(world, driver_name, 2);
  if (d.size() > 0) p.driver.lateral_amplitude_m = d[0];
  if (d.size() > 1) p.driver.speed_wobble = d[1];
  if (const std::string e = validate(p.driver); !e.empty()) {
    throw physics::WorldError("custom numeric '" + driver_name + "': " + e);
  }
  return p;
}

std::optional<BalloonArena> balloon_arena(const physics::World& world) {
  const std::vector<double> a = numeric(world, "uavsim:balloon_arena", 6);
  if (a.empty()) return std::nullopt;
  if (a.size() < 4 || !(a[2] > a[0]) || !(a[3] > a[1])) {
    throw physics::WorldError(
        "custom numeric 'uavsim:balloon_arena' needs x_min y_min x_max y_max with max > min");
  }
  BalloonArena arena;
  arena.min_enu_m = Eigen::Vector2d(a[0], a[1]);
  arena.max_enu_m = Eigen::Vector2d(a[2], a[3]);
  if (a.size() > 4) arena.min_separation_m = a[4];
  if (a.size() > 5) arena.clearance_m = a[5];
  return arena;
}

}  // namespace

ObjectSet create_world_objects(sim::Simulation& sim) {
  physics::World& world = sim.world();
  ObjectSet set;
  std::vector<std::string> balloons;
  for (const auto& [text_name, type] : physics::custom_texts(world, kObjectPrefix)) {
    const std::string name = text_name.substr(std::string(kObjectPrefix).size());
    if (type == "truck") {
      auto truck = std::make_unique<Truck>(sim, truck_params(world, name));
      set.trucks.push_back(&sim.own(std::move(truck)));
    } else if (type == "balloon") {
      balloons.push_back(name);
    } else {
      throw physics::WorldError("custom text '" + text_name + "': unknown object type '" + type +
                                "' (known: truck, balloon)");
    }
  }
  if (!balloons.empty()) {
    auto field = std::make_unique<BalloonField>(sim, balloons, balloon_arena(world), sim.config().field.balloons);
    set.balloons = &sim.own(std::move(field));
  }

  std::vector<Gimbal> gimbals;
  for (const auto& [text_name, data] : physics::custom_texts(world, kGimbalPrefix)) {
    Gimbal g;
    g.name = text_name.substr(std::string(kGimbalPrefix).size());
    std::istringstream in(data);
    std::string vehicle, mode = "down";
    in >> vehicle >> mode;
    g.body_id = world.body_id(g.name);
    if (g.body_id < 0 || physics::mocap_index(world, g.body_id) < 0) {
      throw physics::WorldError("custom text '" + text_name + "': no mocap body named '" + g.name + "'");
    }
    for (size_t i = 0; i < sim.vehicle_count(); ++i) {
      if (sim.vehicle_name(i) == vehicle) g.vehicle = static_cast<int>(i);
    }
    if (g.vehicle < 0) {
      throw physics::WorldError("custom text '" + text_name + "': no vehicle named '" + vehicle + "'");
    }
    if (mode == "down") {
      g.mode = GimbalMode::kDown;
    } else if (mode == "forward") {
      g.mode = GimbalMode::kForward;
    } else if (mode == "targets") {
      g.mode = GimbalMode::kTargets;
    } else {
      throw physics::WorldError("custom text '" + text_name + "': mode '" + mode +
                                "' is not one of down, forward, targets");
    }
    // the mount: an explicit offset "x y z" after the mode, else the site VEHICLE/camera_mount
    double offset[3];
    if (in >> offset[0] >> offset[1] >> offset[2]) {
      g.mount_body_m = Eigen::Vector3d(offset[0], offset[1], offset[2]);
    } else {
      g.mount_body_m = physics::site_position_in_body(world, vehicle + "/camera_mount")
                           .value_or(Eigen::Vector3d::Zero());
    }
    gimbals.push_back(g);
  }
  if (!gimbals.empty()) {
    auto set_ptr = std::make_unique<GimbalSet>(std::move(gimbals), sim.config().field.gimbal);
    set_ptr->before_step(sim);
    set.gimbals = &sim.own(std::move(set_ptr));
  }
  return set;
}

void schedule_world_objects(sim::Simulation& sim, const ObjectSet& set) {
  for (Truck* truck : set.trucks) sim.schedule_object("truck." + truck->params().name, *truck);
  if (set.balloons != nullptr) sim.schedule_object("balloons", *set.balloons);
  if (set.gimbals != nullptr) {
    sim.schedule_object("gimbals", *set.gimbals);
    set.gimbals->schedule_capture_pose(sim);
  }
}

ObjectSet add_world_objects(sim::Simulation& sim) {
  ObjectSet set = create_world_objects(sim);
  schedule_world_objects(sim, set);
  return set;
}

}  // namespace uavsim::server::objects
