// MuJoCo-side helpers for world objects (server/src/objects): kinematic (mocap) body poses, vehicle
// free-body state overrides, geom lookups and switching a geom off. Kept here because only physics/
// includes mujoco.h; every function is loop-thread only, like the World it works on.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "physics/world.hpp"

namespace uavsim::server::physics {

// The mocap index of a body, or -1 if the body is not a mocap body (or does not exist).
int mocap_index(const World& world, int body_id);

// Places a mocap body (kinematic: it moves where it is put, nothing pushes it). Returns false if the
// body is not a mocap body. Takes effect at the next mj_step / mj_forward.
bool set_mocap_pose(World& world, int body_id, const Eigen::Vector3d& pos_enu_m,
                    const Eigen::Quaterniond& q_enu_body);

// A body's pose in the world from the last kinematics pass (xpos, xquat).
Eigen::Vector3d body_position_enu_m(const World& world, int body_id);
Eigen::Quaterniond body_orientation_enu(const World& world, int body_id);

// Overrides a vehicle's free-body state: position, attitude, world-frame linear velocity and
// body-frame angular velocity (e.g. a vehicle carried by a truck).
void set_vehicle_state(World& world, size_t vehicle, const Eigen::Vector3d& pos_enu_m,
                       const Eigen::Quaterniond& q_enu_body, const Eigen::Vector3d& velocity_enu_m_s,
                       const Eigen::Vector3d& rate_body_rad_s);

// Geoms of a body (ids), in model order.
std::vector<int> body_geoms(const World& world, int body_id);
// The top of a box geom (or the highest point of its bounding box) above its body's origin.
double box_top_in_body_m(const World& world, int geom_id);
// A geom's position in its body's frame, and its size[0] (the radius of a sphere).
Eigen::Vector3d geom_position_in_body_m(const World& world, int geom_id);
double geom_radius_m(const World& world, int geom_id);
// A geom's name without its instance prefix ("uav0/blade2" -> "blade2").
std::string geom_local_name(const World& world, int geom_id);
// A site's position in a body's frame, or nullopt if there is no site of that name.
std::optional<Eigen::Vector3d> site_position_in_body(const World& world, const std::string& site_name);

// Collision and visibility switches of a geom, saved so that it can be switched back on.
struct GeomSwitch {
  int geom = -1;
  int contype = 0;
  int conaffinity = 0;
  float alpha = 1.0f;
  int group = 0;
};
// Reads the current switches of a geom.
GeomSwitch geom_switch(const World& world, int geom_id);
// Makes a geom collide and show as saved in s (enabled) or neither collide nor show (disabled).
void set_geom_enabled(World& world, const GeomSwitch& s, bool enabled);

// Custom numeric data by name (empty if none) and custom texts whose name starts with a prefix
// (name, data) in model order.
std::vector<double> custom_numeric(const World& world, const std::string& name);
std::vector<std::pair<std::string, std::string>> custom_texts(const World& world, const std::string& prefix);

}  // namespace uavsim::server::physics
