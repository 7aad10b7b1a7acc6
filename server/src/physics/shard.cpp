#include "physics/shard.hpp"

#include <mujoco/mujoco.h>

#include <algorithm>
#include <cstring>
#include <map>
#include <sstream>

namespace uavsim::server::physics {

namespace {

constexpr const char* kVehicleTextPrefix = "uavsim:vehicle:";
constexpr int kRotorUserFields =
    5;  // spin_dir max_thrust_n torque_coef_m time_const_s prop_diameter_m
// The collision bit that moving geoms carry in contype and parked vehicles' geoms in conaffinity
// (and nothing else), so that only something that moves touches a parked vehicle (models/README.md
// reserves it).
constexpr int kWakeBit = 1 << 30;
// A vehicle whose geoms are this close to static geometry at the start rests on it.
constexpr double kRestingMargin_m = 0.005;

std::string name_of(const mjModel* m, int type, int id) {
  const char* n = mj_id2name(m, type, id);
  return n ? n : "";
}

// numeric custom field uavsim:VEHICLE:FIELD, or an empty vector
std::vector<double> custom_numeric(const mjModel* m, const std::string& vehicle,
                                   const char* field) {
  const std::string name = "uavsim:" + vehicle + ":" + field;
  const int id = mj_name2id(m, mjOBJ_NUMERIC, name.c_str());
  if (id < 0) return {};
  const mjtNum* data = m->numeric_data + m->numeric_adr[id];
  return std::vector<double>(data, data + m->numeric_size[id]);
}

}  // namespace

std::unique_ptr<Shard> Shard::from_mjcf(const std::string& mjcf, const std::string& label) {
  // load the text through a virtual file; asset paths in it are absolute (see world_composer)
  auto vfs = std::make_unique<mjVFS>();
  mj_defaultVFS(vfs.get());
  const char* kName = "uavsim_world.xml";
  if (mj_makeEmptyFileVFS(vfs.get(), kName, static_cast<int>(mjcf.size())) != 0) {
    throw WorldError(label + ": cannot create the in-memory world file");
  }
  const int index = mj_findFileVFS(vfs.get(), kName);
  std::memcpy(vfs->filedata[index], mjcf.data(), mjcf.size());
  char error[1024] = "";
  mjModel* m = mj_loadXML(kName, vfs.get(), error, sizeof(error));
  mj_deleteVFS(vfs.get());
  if (m == nullptr) {
    throw WorldError(label +
                     ": MuJoCo rejected the composed world (write it with --write-world to " +
                     "see the line): " + error);
  }
  mjData* d = mj_makeData(m);
  return std::unique_ptr<Shard>(new Shard(m, d, label));
}

Shard::Shard(mjModel* m, mjData* d, const std::string& label) : m_(m), d_(d) {
  try {
    find_vehicles(label);
    init_parking();
  } catch (...) {
    mj_deleteData(d_);
    mj_deleteModel(m_);
    throw;
  }
  park_resting();
  mj_forward(m_, d_);
}

Shard::~Shard() {
  mj_deleteData(d_);
  mj_deleteModel(m_);
}

void Shard::find_vehicles(const std::string& label) {
  const mjModel* m = m_;
  body_vehicle_.assign(m->nbody, -1);
  geom_is_gear_.assign(m->ngeom, 0);

  // vehicles: every custom text named uavsim:vehicle:BODY, in model order (the order of the world
  // file)
  for (int t = 0; t < m->ntext; ++t) {
    const std::string tname = name_of(m, mjOBJ_TEXT, t);
    if (tname.rfind(kVehicleTextPrefix, 0) != 0) continue;
    VehicleBinding v;
    v.name = tname.substr(std::strlen(kVehicleTextPrefix));
    v.body_id = mj_name2id(m, mjOBJ_BODY, v.name.c_str());
    if (v.body_id < 0) throw WorldError(label + ": " + tname + " names no body '" + v.name + "'");
    const int jnt = m->body_jntadr[v.body_id];
    if (jnt < 0 || m->jnt_type[jnt] != mjJNT_FREE) {
      throw WorldError(label + ": vehicle body '" + v.name +
                       "' needs a free joint as its first joint");
    }
    v.qpos_adr = m->jnt_qposadr[jnt];
    v.dof_adr = m->jnt_dofadr[jnt];

    airframe::AirframeParams& a = v.airframe;
    a.frame = std::string(m->text_data + m->text_adr[t]);
    a.mass_kg = m->body_subtreemass[v.body_id];
    a.inertia_body_kgm2 = Eigen::Vector3d(m->body_inertia + 3 * v.body_id).asDiagonal();
    a.com_body_m = Eigen::Vector3d(m->body_ipos + 3 * v.body_id);

    // rotors: sites rotor0, rotor1, ... of the vehicle body, parameters in their user data
    for (int k = 0;; ++k) {
      const std::string sname = v.name + "/rotor" + std::to_string(k);
      const int s = mj_name2id(m, mjOBJ_SITE, sname.c_str());
      if (s < 0) break;
      if (m->site_bodyid[s] != v.body_id) {
        throw WorldError(label + ": rotor site '" + sname + "' must belong to body '" + v.name +
                         "'");
      }
      if (m->nuser_site < kRotorUserFields) {
        throw WorldError(label + ": rotor sites need <size nuser_site=\"5\"/> user data");
      }
      const mjtNum* u = m->site_user + m->nuser_site * s;
      airframe::RotorParams r;
      r.position_body_m = Eigen::Vector3d(m->site_pos + 3 * s);
      r.spin_dir = u[0] >= 0 ? 1 : -1;
      r.max_thrust_n = u[1];
      r.torque_coef_m = u[2];
      r.time_const_s = u[3];
      r.prop_diameter_m = u[4];
      if (!(r.max_thrust_n > 0) || !(r.time_const_s > 0) || !(r.prop_diameter_m > 0)) {
        throw WorldError(label + ": rotor site '" + sname +
                         "' needs user=\"spin_dir max_thrust_n torque_coef_m time_const_s "
                         "prop_diameter_m\" with positive values");
      }
      a.rotors.push_back(r);
    }
    if (a.rotors.size() < 3) {
      throw WorldError(label + ": vehicle '" + v.name + "' has " + std::to_string(a.rotors.size()) +
                       " rotor sites (" + v.name + "/rotor0, ...); a multirotor needs at least 3");
    }
    if (auto lin = custom_numeric(m, v.name, "drag_lin"); lin.size() == 3) {
      a.drag_lin_n_per_m_s = Eigen::Vector3d(lin.data());
    }
    if (auto quad = custom_numeric(m, v.name, "drag_quad"); quad.size() == 3) {
      a.drag_quad_n_per_m2_s2 = Eigen::Vector3d(quad.data());
    }
    if (auto bat = custom_numeric(m, v.name, "battery"); bat.size() >= 2) {
      a.battery.capacity_mah = bat[0];
      a.battery.control_power_w = bat[1];
      if (bat.size() >= 3) a.battery.internal_resistance_ohm = bat[2];
    }
    vehicles_.push_back(std::move(v));
  }

  // body -> vehicle (through the root body), and which geoms are landing gear
  std::map<int, int> root_vehicle;
  for (size_t i = 0; i < vehicles_.size(); ++i)
    root_vehicle[vehicles_[i].body_id] = static_cast<int>(i);
  for (int b = 0; b < m->nbody; ++b) {
    auto it = root_vehicle.find(m->body_rootid[b]);
    if (it != root_vehicle.end()) body_vehicle_[b] = it->second;
  }
  for (int g = 0; g < m->ngeom; ++g) {
    const std::string gname = name_of(m, mjOBJ_GEOM, g);
    const size_t slash = gname.rfind('/');
    const std::string local = slash == std::string::npos ? gname : gname.substr(slash + 1);
    geom_is_gear_[g] = local.rfind("gear", 0) == 0 ? 1 : 0;
  }
}

void Shard::init_parking() {
  const mjModel* m = m_;
  // a body moves if it has a joint between it and the world, or rides on a kinematic (mocap) body
  body_static_.assign(m->nbody, 0);
  for (int b = 0; b < m->nbody; ++b) {
    bool moves = m->body_weldid[b] != 0;
    for (int a = b; a > 0 && !moves; a = m->body_parentid[a]) moves = m->body_mocapid[a] >= 0;
    body_static_[b] = moves ? 0 : 1;
  }
  // each vehicle's collidable geoms, and the (contype, conaffinity) pairs they use
  parked_.assign(vehicles_.size(), Parking{});
  std::vector<std::pair<int, int>> vehicle_bits;
  for (int g = 0; g < m->ngeom; ++g) {
    const int ct = m->geom_contype[g], ca = m->geom_conaffinity[g];
    if ((ct | ca) & kWakeBit) {
      throw WorldError("geom '" + name_of(m, mjOBJ_GEOM, g) +
                       "' uses collision bit 30 (contype/conaffinity " + std::to_string(kWakeBit) +
                       "), which uavsim reserves for parked vehicles");
    }
    const int v = body_vehicle_[m->geom_bodyid[g]];
    if (v < 0 || (ct | ca) == 0) continue;
    parked_[v].geoms.push_back(g);
    if (std::find(vehicle_bits.begin(), vehicle_bits.end(), std::make_pair(ct, ca)) ==
        vehicle_bits.end()) {
      vehicle_bits.emplace_back(ct, ca);
    }
  }
  // moving geoms that can touch some vehicle geom can touch (and wake) a parked vehicle
  for (int g = 0; g < m->ngeom; ++g) {
    if (body_static_[m->geom_bodyid[g]]) continue;
    const int ct = m->geom_contype[g], ca = m->geom_conaffinity[g];
    for (const auto& [vct, vca] : vehicle_bits) {
      if ((ct & vca) || (vct & ca)) {
        m_->geom_contype[g] |= kWakeBit;
        break;
      }
    }
  }
  geom_contype0_.assign(m->geom_contype, m->geom_contype + m->ngeom);
  geom_conaffinity0_.assign(m->geom_conaffinity, m->geom_conaffinity + m->ngeom);
}

void Shard::set_parked_bits(size_t vehicle, bool parked) {
  for (int g : parked_[vehicle].geoms) {
    m_->geom_contype[g] = parked ? 0 : geom_contype0_[g];
    m_->geom_conaffinity[g] = parked ? kWakeBit : geom_conaffinity0_[g];
  }
}

void Shard::park(size_t vehicle) {
  Parking& p = parked_[vehicle];
  if (p.on) return;
  const VehicleBinding& v = vehicles_[vehicle];
  std::copy(d_->qpos + v.qpos_adr, d_->qpos + v.qpos_adr + 7, p.qpos);
  std::fill(d_->qvel + v.dof_adr, d_->qvel + v.dof_adr + 6, 0.0);
  std::fill(d_->qfrc_applied + v.dof_adr, d_->qfrc_applied + v.dof_adr + 6, 0.0);
  set_parked_bits(vehicle, true);
  p.on = true;
  ++parked_count_;
  forwarded_ = false;
}

void Shard::wake(size_t vehicle) {
  Parking& p = parked_[vehicle];
  if (!p.on) return;
  set_parked_bits(vehicle, false);
  p.on = false;
  --parked_count_;
  forwarded_ = false;
}

void Shard::park_resting() {
  // contacts of the initial pose, with the vehicles' margins widened so that gear standing exactly
  // on the ground (distance 0) counts
  mj_kinematics(m_, d_);
  std::vector<std::pair<int, mjtNum>> margins;
  for (const Parking& p : parked_) {
    for (int g : p.geoms) {
      margins.emplace_back(g, m_->geom_margin[g]);
      m_->geom_margin[g] = std::max(m_->geom_margin[g], kRestingMargin_m);
    }
  }
  mj_collision(m_, d_);
  for (const auto& [g, margin] : margins) m_->geom_margin[g] = margin;
  std::vector<int> support(vehicles_.size(),
                           0);  // static contacts, or -1 once anything moving touches
  for (int i = 0; i < d_->ncon; ++i) {
    const mjContact& c = d_->contact[i];
    const int b[2] = {m_->geom_bodyid[c.geom1], m_->geom_bodyid[c.geom2]};
    for (int side = 0; side < 2; ++side) {
      const int v = body_vehicle_[b[side]];
      if (v < 0 || v == body_vehicle_[b[1 - side]] || support[v] < 0) continue;
      support[v] = body_static_[b[1 - side]] ? support[v] + 1 : -1;
    }
  }
  d_->ncon = 0;
  for (size_t v = 0; v < vehicles_.size(); ++v) {
    const mjtNum* dq = d_->qvel + vehicles_[v].dof_adr;
    const bool still = std::all_of(dq, dq + 6, [](mjtNum x) { return x == 0.0; });
    if (support[v] > 0 && still) park(v);
  }
}

void Shard::hold_parked() {
  woken_.clear();
  if (parked_count_ == 0) return;
  // something moving touched a parked vehicle: it wakes with the state this step gave it
  for (int i = 0; i < d_->ncon; ++i) {
    const mjContact& c = d_->contact[i];
    for (int g : {c.geom1, c.geom2}) {
      const int v = body_vehicle_[m_->geom_bodyid[g]];
      if (v >= 0 && parked_[v].on) woken_.push_back(v);
    }
  }
  std::sort(woken_.begin(), woken_.end());
  woken_.erase(std::unique(woken_.begin(), woken_.end()), woken_.end());
  for (int v : woken_) wake(static_cast<size_t>(v));
  // the others go back exactly where they are held, at rest
  for (size_t v = 0; v < vehicles_.size(); ++v) {
    if (!parked_[v].on) continue;
    std::copy(parked_[v].qpos, parked_[v].qpos + 7, d_->qpos + vehicles_[v].qpos_adr);
    std::fill(d_->qvel + vehicles_[v].dof_adr, d_->qvel + vehicles_[v].dof_adr + 6, 0.0);
  }
}

int Shard::buffer_overflows() const {
  return d_->warning[mjWARN_CONTACTFULL].number + d_->warning[mjWARN_CNSTRFULL].number;
}

double Shard::time_s() const { return d_->time; }
double Shard::timestep_s() const { return m_->opt.timestep; }
void Shard::set_timestep_s(double dt_s) { m_->opt.timestep = dt_s; }

airframe::TruthState Shard::truth(size_t vehicle) const {
  const VehicleBinding& v = vehicles_[vehicle];
  const mjtNum* q = d_->qpos + v.qpos_adr;
  const mjtNum* dq = d_->qvel + v.dof_adr;
  const mjtNum* ddq = d_->qacc + v.dof_adr;
  airframe::TruthState s;
  if (parked_[vehicle].on) {
    // held at rest: no velocity, no acceleration (the accelerometer reads 1 g up, as on the ground)
    const double* h = parked_[vehicle].qpos;
    s.position_enu_m = Eigen::Vector3d(h[0], h[1], h[2]);
    s.q_enu_body = Eigen::Quaterniond(h[3], h[4], h[5], h[6]).normalized();
    return s;
  }
  s.position_enu_m = Eigen::Vector3d(q[0], q[1], q[2]);
  s.q_enu_body = Eigen::Quaterniond(q[3], q[4], q[5], q[6]).normalized();
  // free joint: linear velocity in the world frame, angular velocity in the body frame
  s.velocity_enu_m_s = Eigen::Vector3d(dq[0], dq[1], dq[2]);
  s.rate_body_rad_s = Eigen::Vector3d(dq[3], dq[4], dq[5]);
  s.accel_enu_m_s2 = Eigen::Vector3d(ddq[0], ddq[1], ddq[2]);
  return s;
}

void Shard::apply_wrench(size_t vehicle, const airframe::Wrench& wrench) {
  mjtNum* f = d_->qfrc_applied + vehicles_[vehicle].dof_adr;
  f[0] = wrench.force_enu_n.x();
  f[1] = wrench.force_enu_n.y();
  f[2] = wrench.force_enu_n.z();
  f[3] = wrench.torque_body_nm.x();
  f[4] = wrench.torque_body_nm.y();
  f[5] = wrench.torque_body_nm.z();
}

void Shard::set_pose(size_t vehicle, const double pos_enu_m[3], const double quat_wxyz[4]) {
  wake(vehicle);
  const VehicleBinding& v = vehicles_[vehicle];
  std::copy(pos_enu_m, pos_enu_m + 3, d_->qpos + v.qpos_adr);
  std::copy(quat_wxyz, quat_wxyz + 4, d_->qpos + v.qpos_adr + 3);
  std::fill(d_->qvel + v.dof_adr, d_->qvel + v.dof_adr + 6, 0.0);
}

void Shard::step() {
  // nothing can move: every dof is a parked vehicle's, nothing kinematic or actuated; only the
  // clock runs (with the kinematics made current once, for cameras and queries)
  if (parked_count_ > 0 && parked_count_ == vehicles_.size() &&
      m_->nv == 6 * static_cast<int>(parked_count_) && m_->nmocap == 0 && m_->nu == 0) {
    woken_.clear();
    if (!forwarded_) {
      mj_forward(m_, d_);
      forwarded_ = true;
    }
    d_->time += m_->opt.timestep;
    return;
  }
  mj_step(m_, d_);
  hold_parked();
}

void Shard::vehicle_contacts(int shard, int first_vehicle, std::vector<VehicleContact>* out) const {
  for (int i = 0; i < d_->ncon; ++i) {
    const mjContact& c = d_->contact[i];
    const int g[2] = {c.geom1, c.geom2};
    const int b[2] = {m_->geom_bodyid[g[0]], m_->geom_bodyid[g[1]]};
    const int v[2] = {body_vehicle_[b[0]], body_vehicle_[b[1]]};
    for (int side = 0; side < 2; ++side) {
      if (v[side] < 0) continue;
      if (v[side] == v[1 - side]) continue;  // a vehicle touching itself
      VehicleContact vc;
      vc.vehicle = first_vehicle + v[side];
      vc.other_vehicle = v[1 - side] < 0 ? -1 : first_vehicle + v[1 - side];
      vc.shard = shard;
      vc.landing_gear = geom_is_gear_[g[side]] != 0;
      vc.geom = g[side];
      vc.other_geom = g[1 - side];
      vc.other_body = b[1 - side];
      vc.other_static = body_static_[b[1 - side]] != 0;
      out->push_back(vc);
    }
  }
}

void Shard::reset() {
  mj_resetData(m_, d_);
  for (size_t v = 0; v < parked_.size(); ++v) wake(v);
  park_resting();
  mj_forward(m_, d_);
}

std::string Shard::body_name(int body_id) const { return name_of(m_, mjOBJ_BODY, body_id); }
std::string Shard::geom_name(int geom_id) const { return name_of(m_, mjOBJ_GEOM, geom_id); }
int Shard::body_id(const std::string& name) const {
  return mj_name2id(m_, mjOBJ_BODY, name.c_str());
}

bool Shard::vehicle_visual_only(int geom_id) const {
  if (geom_id < 0 || geom_id >= m_->ngeom) return false;
  const size_t g = static_cast<size_t>(geom_id);
  return body_vehicle_[static_cast<size_t>(m_->geom_bodyid[g])] >= 0 && geom_contype0_[g] == 0 &&
         geom_conaffinity0_[g] == 0;
}

}  // namespace uavsim::server::physics
