#include "physics/world.hpp"

#include <mujoco/mujoco.h>

#include <algorithm>
#include <thread>

#include "physics/shard.hpp"
#include "physics/step_pool.hpp"

namespace uavsim::server::physics {

std::unique_ptr<World> World::load(const std::string& world_path, const ComposeOptions& options,
                                   const ShardOptions& shards) {
  if (shards.shards == 1) return from_mjcf(compose_world(world_path, options), world_path);
  if (shards.threads < 0 || shards.threads > kMaxPhysicsShards) {
    throw WorldError(world_path + ": " + std::to_string(shards.threads) + " physics threads: must be 1 to " +
                     std::to_string(kMaxPhysicsShards) + " (or 0: one per shard)");
  }
  return from_shards(compose_world_shards(world_path, options, shards.shards), world_path, shards.threads);
}

std::unique_ptr<World> World::from_mjcf(const std::string& mjcf, const std::string& label) {
  return from_shards({mjcf}, label, 1);
}

std::unique_ptr<World> World::from_shards(const std::vector<std::string>& mjcf, const std::string& label,
                                          int threads) {
  if (mjcf.empty() || mjcf.size() > static_cast<size_t>(kMaxPhysicsShards)) {
    throw WorldError(label + ": " + std::to_string(mjcf.size()) + " physics shards: must be 1 to " +
                     std::to_string(kMaxPhysicsShards));
  }
  std::vector<std::unique_ptr<Shard>> shards;
  for (size_t k = 0; k < mjcf.size(); ++k) {
    shards.push_back(Shard::from_mjcf(mjcf[k], mjcf.size() == 1 ? label : label + " (shard " + std::to_string(k) + ")"));
  }
  if (threads == 0) threads = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  threads = std::clamp(threads, 1, static_cast<int>(shards.size()));
  return std::unique_ptr<World>(new World(std::move(shards), threads));
}

World::World(std::vector<std::unique_ptr<Shard>> shards, int threads)
    : shards_(std::move(shards)), pool_(std::make_unique<StepPool>(threads)) {
  // the world's vehicles: the shards' blocks one after another
  for (size_t k = 0; k < shards_.size(); ++k) {
    first_.push_back(vehicles_.size());
    for (VehicleBinding v : shards_[k]->vehicles()) {
      v.shard = static_cast<int>(k);
      vehicles_.push_back(std::move(v));
    }
  }
  parked_.assign(vehicles_.size(), 0);
  for (size_t k = 0; k < shards_.size(); ++k) sync_parked(k);
}

void World::sync_parked(size_t k) {
  const Shard& s = *shards_[k];
  for (size_t v = 0; v < s.vehicles().size(); ++v) parked_[first_[k] + v] = s.parked(v) ? 1 : 0;
}

World::~World() = default;

const mjModel* World::model() const { return shards_[0]->model(); }
mjModel* World::mutable_model() { return shards_[0]->model(); }
mjData* World::data() { return shards_[0]->data(); }
const mjData* World::data() const { return shards_[0]->data(); }
bool World::vehicle_visual_only(int geom) const { return shards_[0]->vehicle_visual_only(geom); }
int World::thread_count() const { return pool_->threads(); }

Shard& World::shard_of(size_t vehicle) const { return *shards_[static_cast<size_t>(vehicles_[vehicle].shard)]; }

void World::for_each_shard_block(const std::function<void(size_t first, size_t end)>& fn) {
  if (pool_->threads() == 1) {
    fn(0, vehicles_.size());
    return;
  }
  pool_->run(shard_count(), [&](int k) {
    const size_t first = first_[static_cast<size_t>(k)];
    fn(first, first + shards_[static_cast<size_t>(k)]->vehicles().size());
  });
}

double World::time_s() const { return shards_[0]->time_s(); }
double World::timestep_s() const { return shards_[0]->timestep_s(); }
void World::set_timestep_s(double dt_s) {
  for (auto& s : shards_) s->set_timestep_s(dt_s);
}

airframe::TruthState World::truth(size_t vehicle) const {
  return shard_of(vehicle).truth(local(vehicle));
}
void World::apply_wrench(size_t vehicle, const airframe::Wrench& wrench) {
  shard_of(vehicle).apply_wrench(local(vehicle), wrench);
}
void World::set_pose(size_t vehicle, const double pos_enu_m[3], const double quat_wxyz[4]) {
  shard_of(vehicle).set_pose(local(vehicle), pos_enu_m, quat_wxyz);
  parked_[vehicle] = 0;  // set_pose wakes it
}

void World::step(const std::function<void(size_t first, size_t end)>& before_each_shard) {
  // every shard one step (after its vehicles' own work), each on its own thread of the pool; then the
  // woken vehicles in world order
  pool_->run(shard_count(), [&](int k) {
    const size_t s = static_cast<size_t>(k);
    if (before_each_shard) before_each_shard(first_[s], first_[s] + shards_[s]->vehicles().size());
    shards_[s]->step();
  });
  woken_.clear();
  for (size_t k = 0; k < shards_.size(); ++k) {
    for (int v : shards_[k]->woken_by_contact()) {
      woken_.push_back(static_cast<int>(first_[k]) + v);
      parked_[first_[k] + static_cast<size_t>(v)] = 0;
    }
  }
}

size_t World::parked_count() const {
  size_t n = 0;
  for (const auto& s : shards_) n += s->parked_count();
  return n;
}
void World::park(size_t vehicle) {
  shard_of(vehicle).park(local(vehicle));
  parked_[vehicle] = 1;
}
void World::wake(size_t vehicle) {
  shard_of(vehicle).wake(local(vehicle));
  parked_[vehicle] = 0;
}
void World::park_resting() {
  for (size_t k = 0; k < shards_.size(); ++k) {
    shards_[k]->park_resting();
    sync_parked(k);
  }
}

int World::buffer_overflows() const {
  int n = 0;
  for (const auto& s : shards_) n += s->buffer_overflows();
  return n;
}

void World::vehicle_contacts(std::vector<VehicleContact>* out) const {
  out->clear();
  for (size_t k = 0; k < shards_.size(); ++k) {
    shards_[k]->vehicle_contacts(static_cast<int>(k), static_cast<int>(first_[k]), out);
  }
}

void World::reset() {
  for (size_t k = 0; k < shards_.size(); ++k) {
    shards_[k]->reset();
    sync_parked(k);
  }
  woken_.clear();
}

std::string World::body_name(int body_id, int shard) const { return shards_.at(static_cast<size_t>(shard))->body_name(body_id); }
std::string World::geom_name(int geom_id, int shard) const { return shards_.at(static_cast<size_t>(shard))->geom_name(geom_id); }
int World::body_id(const std::string& name) const { return shards_[0]->body_id(name); }

}  // namespace uavsim::server::physics
