#include "physics/object_bodies.hpp"

#include <mujoco/mujoco.h>

#include <cstring>

namespace uavsim::server::physics {

int mocap_index(const World& world, int body_id) {
  const mjModel* m = world.model();
  if (body_id < 0 || body_id >= m->nbody) return -1;
  return m->body_mocapid[body_id];
}

bool set_mocap_pose(World& world, int body_id, const Eigen::Vector3d& pos_enu_m,
                    const Eigen::Quaterniond& q_enu_body) {
  const int k = mocap_index(world, body_id);
  if (k < 0) return false;
  mjData* d = world.data();
  mjtNum* p = d->mocap_pos + 3 * k;
  mjtNum* q = d->mocap_quat + 4 * k;
  p[0] = pos_enu_m.x();
  p[1] = pos_enu_m.y();
  p[2] = pos_enu_m.z();
  q[0] = q_enu_body.w();
  q[1] = q_enu_body.x();
  q[2] = q_enu_body.y();
  q[3] = q_enu_body.z();
  return true;
}

Eigen::Vector3d body_position_enu_m(const World& world, int body_id) {
  const mjtNum* p = world.data()->xpos + 3 * body_id;
  return Eigen::Vector3d(p[0], p[1], p[2]);
}

Eigen::Quaterniond body_orientation_enu(const World& world, int body_id) {
  const mjtNum* q = world.data()->xquat + 4 * body_id;
  return Eigen::Quaterniond(q[0], q[1], q[2], q[3]);
}

void set_vehicle_state(World& world, size_t vehicle, const Eigen::Vector3d& pos_enu_m,
                       const Eigen::Quaterniond& q_enu_body, const Eigen::Vector3d& velocity_enu_m_s,
                       const Eigen::Vector3d& rate_body_rad_s) {
  world.wake(vehicle);  // a vehicle that is moved is no longer held
  const VehicleBinding& v = world.vehicles()[vehicle];
  mjData* d = world.data();
  mjtNum* q = d->qpos + v.qpos_adr;
  mjtNum* dq = d->qvel + v.dof_adr;
  // free joint: qpos = position, quaternion (w x y z); qvel = world linear, body angular velocity
  q[0] = pos_enu_m.x();
  q[1] = pos_enu_m.y();
  q[2] = pos_enu_m.z();
  q[3] = q_enu_body.w();
  q[4] = q_enu_body.x();
  q[5] = q_enu_body.y();
  q[6] = q_enu_body.z();
  for (int i = 0; i < 3; ++i) {
    dq[i] = velocity_enu_m_s[i];
    dq[3 + i] = rate_body_rad_s[i];
  }
}

std::vector<int> body_geoms(const World& world, int body_id) {
  const mjModel* m = world.model();
  std::vector<int> out;
  if (body_id < 0 || body_id >= m->nbody) return out;
  for (int g = m->body_geomadr[body_id]; g >= 0 && g < m->body_geomadr[body_id] + m->body_geomnum[body_id];
       ++g) {
    out.push_back(g);
  }
  return out;
}

double box_top_in_body_m(const World& world, int geom_id) {
  const mjModel* m = world.model();
  // a box: centre height plus half height (a deck is not rotated); otherwise the bounding sphere
  const mjtNum* pos = m->geom_pos + 3 * geom_id;
  if (m->geom_type[geom_id] == mjGEOM_BOX) return pos[2] + m->geom_size[3 * geom_id + 2];
  return pos[2] + m->geom_rbound[geom_id];
}

Eigen::Vector3d geom_position_in_body_m(const World& world, int geom_id) {
  const mjtNum* p = world.model()->geom_pos + 3 * geom_id;
  return Eigen::Vector3d(p[0], p[1], p[2]);
}

double geom_radius_m(const World& world, int geom_id) { return world.model()->geom_size[3 * geom_id]; }

std::string geom_local_name(const World& world, int geom_id) {
  const std::string name = world.geom_name(geom_id);
  const size_t slash = name.rfind('/');
  return slash == std::string::npos ? name : name.substr(slash + 1);
}

std::optional<Eigen::Vector3d> site_position_in_body(const World& world, const std::string& site_name) {
  const mjModel* m = world.model();
  const int s = mj_name2id(m, mjOBJ_SITE, site_name.c_str());
  if (s < 0) return std::nullopt;
  return Eigen::Vector3d(m->site_pos[3 * s], m->site_pos[3 * s + 1], m->site_pos[3 * s + 2]);
}

GeomSwitch geom_switch(const World& world, int geom_id) {
  const mjModel* m = world.model();
  GeomSwitch s;
  s.geom = geom_id;
  s.contype = m->geom_contype[geom_id];
  s.conaffinity = m->geom_conaffinity[geom_id];
  s.alpha = m->geom_rgba[4 * geom_id + 3];
  s.group = m->geom_group[geom_id];
  return s;
}

void set_geom_enabled(World& world, const GeomSwitch& s, bool enabled) {
  mjModel* m = world.mutable_model();
  m->geom_contype[s.geom] = enabled ? s.contype : 0;
  m->geom_conaffinity[s.geom] = enabled ? s.conaffinity : 0;
  m->geom_rgba[4 * s.geom + 3] = enabled ? s.alpha : 0.0f;
  // group 5 is hidden by MuJoCo's default visual options, in case a material sets the colour
  m->geom_group[s.geom] = enabled ? s.group : 5;
}

std::vector<double> custom_numeric(const World& world, const std::string& name) {
  const mjModel* m = world.model();
  const int id = mj_name2id(m, mjOBJ_NUMERIC, name.c_str());
  if (id < 0) return {};
  const mjtNum* data = m->numeric_data + m->numeric_adr[id];
  return std::vector<double>(data, data + m->numeric_size[id]);
}

std::vector<std::pair<std::string, std::string>> custom_texts(const World& world, const std::string& prefix) {
  const mjModel* m = world.model();
  std::vector<std::pair<std::string, std::string>> out;
  for (int t = 0; t < m->ntext; ++t) {
    const char* n = mj_id2name(m, mjOBJ_TEXT, t);
    if (n == nullptr || std::strncmp(n, prefix.c_str(), prefix.size()) != 0) continue;
    out.emplace_back(n, std::string(m->text_data + m->text_adr[t]));
  }
  return out;
}

}  // namespace uavsim::server::physics
