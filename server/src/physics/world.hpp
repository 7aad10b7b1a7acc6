// The MuJoCo side of the simulation: a loaded world, the vehicles found in it, rotor wrenches written into
// qfrc_applied, ground truth and contacts. The only module (with render/) that includes MuJoCo; this header
// forward-declares MuJoCo's structs so users of World do not see mujoco.h.
//
// Physics shards: a world of many vehicles can be split into several shards (world_composer.hpp
// compose_world_shards), each its own mjModel + mjData with a block of the vehicles and the whole static
// scene, stepped in lockstep on a small thread pool (one step of every shard, then the next). The contact
// rule: vehicles in the same shard collide with each other; vehicles in different shards never touch each
// other (they pass through each other); every vehicle collides with the static scene, which every shard
// holds. Only worlds whose sole moving things are vehicles can be sharded (the composer refuses others), so
// nothing else moving is ever split from what it must touch. Each shard is stepped by exactly one thread
// and shards share no state, so results depend on the number of shards but never on the number of
// threads. One shard (the default) is exactly the unsharded world.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "airframe/airframe.hpp"
#include "airframe/truth_state.hpp"
#include "physics/world_composer.hpp"

struct mjModel_;
struct mjData_;

namespace uavsim::server::physics {

class Shard;
class StepPool;

// How a world is split and stepped. Out-of-range values are errors (WorldError), never clamped silently.
struct ShardOptions {
  int shards = 1;   // 1 to kMaxPhysicsShards, or 0: auto (world_composer.hpp)
  int threads = 0;  // threads stepping the shards, 1 to kMaxPhysicsShards; 0: one per shard, at most the
                    // hardware threads. More threads than shards are not started.
};

// A vehicle found in the world (models/README.md: <text name="uavsim:vehicle:BODY" data="FRAME"/>).
struct VehicleBinding {
  std::string name;  // the body name, e.g. "uav0"
  int body_id = -1;
  int qpos_adr = -1;  // the free joint's 7 qpos
  int dof_adr = -1;   // the free joint's 6 dofs
  int shard = 0;      // the physics shard that holds it; body_id and the addresses are in that shard's model
  airframe::AirframeParams airframe;
};

// A contact that involves at least one vehicle, from the last step.
struct VehicleContact {
  int vehicle = -1;        // index into vehicles()
  int other_vehicle = -1;  // -1 when the other side is not a vehicle
  bool landing_gear = false;  // the vehicle's geom is landing gear
  int geom = -1;           // the vehicle's geom
  int other_geom = -1;
  int other_body = -1;     // the other geom's body
  bool other_static = false;  // the other body cannot move (welded to the world, not kinematic)
  int shard = 0;              // the shard whose model the geom and body ids belong to
};

class World {
 public:
  // Composes and loads a world file. Throws WorldError naming the file (and line) on any error.
  // With shards.shards != 1, split into physics shards (see above).
  static std::unique_ptr<World> load(const std::string& world_path, const ComposeOptions& options,
                                     const ShardOptions& shards = {});
  // Loads standalone MJCF text (label names it in errors). Throws WorldError.
  static std::unique_ptr<World> from_mjcf(const std::string& mjcf, const std::string& label);
  // One shard per MJCF text (compose_world_shards' output), stepped by `threads` threads (ShardOptions).
  static std::unique_ptr<World> from_shards(const std::vector<std::string>& mjcf, const std::string& label,
                                            int threads);
  ~World();
  World(const World&) = delete;
  World& operator=(const World&) = delete;

  // Shard 0's model and data: the whole world when it is not sharded. A sharded world holds only
  // vehicles and static geometry, and shard 0 has only its own block of the vehicles: cameras and
  // renderers need an unsharded world.
  const mjModel_* model() const;
  // For run-time model switches (a popped balloon's geoms, physics/object_bodies). Loop thread only.
  mjModel_* mutable_model();
  mjData_* data();
  const mjData_* data() const;
  // Whether geom (of shard 0's model) belongs to a vehicle and touches nothing (contype =
  // conaffinity = 0 as loaded, whether or not its vehicle is parked): a part that is only drawn.
  bool vehicle_visual_only(int geom) const;
  int shard_count() const { return static_cast<int>(shards_.size()); }
  int thread_count() const;
  // Runs fn(first, end) for each shard's block of vehicles [first, end) in the world's indices, each block
  // on the thread that steps that shard, and returns when all have run (one call with every vehicle when
  // there is one thread). fn must touch only those vehicles' state. Loop thread only.
  void for_each_shard_block(const std::function<void(size_t first, size_t end)>& fn);

  const std::vector<VehicleBinding>& vehicles() const { return vehicles_; }
  // A vehicle's airframe, for conditions set before the simulation starts (battery sag). Loop thread only.
  airframe::AirframeParams& mutable_airframe(size_t vehicle) { return vehicles_[vehicle].airframe; }
  double time_s() const;
  double timestep_s() const;
  void set_timestep_s(double dt_s);

  // Ground truth of a vehicle's free body (position and velocity of the body origin).
  airframe::TruthState truth(size_t vehicle) const;
  // Writes a vehicle's wrench about its body origin into its free joint's qfrc_applied dofs:
  // world-frame force in dofs 0-2, body-frame torque in dofs 3-5.
  void apply_wrench(size_t vehicle, const airframe::Wrench& wrench);
  // Places a vehicle (teleport) at rest; used by resets and crash handling in tests.
  void set_pose(size_t vehicle, const double pos_enu_m[3], const double quat_wxyz[4]);

  // Advances physics by one timestep (mj_step; when every dof belongs to a parked vehicle and nothing
  // is kinematic, only the clock advances). Parked vehicles are then put back where they are held;
  // one that something touched wakes instead. With before_each_shard, runs it on each shard's block of
  // vehicles [first, end) just before that shard's mj_step, on the thread that steps the shard (the
  // vehicles' own per-step work joins the shard's physics in one batch of the pool); it must touch
  // only those vehicles' state. Loop thread only.
  void step(const std::function<void(size_t first, size_t end)>& before_each_shard = {});

  // Parking: a vehicle at rest on static geometry is held exactly where it is (qpos fixed, qvel zero)
  // and its geoms stop touching static geometry (no contact constraints: a grounded quad's resting
  // contacts are most of its step), while moving bodies (awake vehicles, kinematic objects) still
  // collide with it and wake it. truth() of a parked vehicle is that pose at rest (zero velocity and
  // acceleration). Loop thread only.
  bool parked(size_t vehicle) const { return parked_[vehicle] != 0; }
  size_t parked_count() const;
  // Holds the vehicle at its present pose, at rest. Parking a parked vehicle does nothing.
  void park(size_t vehicle);
  // Gives the vehicle its contacts back, at rest where it was held.
  void wake(size_t vehicle);
  // Parks every vehicle whose geoms touch (within 5 mm) static geometry only, as at the start of a
  // world: vehicles that start on the ground cost no contacts until they arm.
  void park_resting();
  // Vehicles that the last step woke because something touched them.
  const std::vector<int>& woken_by_contact() const { return woken_; }
  // Times the constraint or contact buffer overflowed (MuJoCo drops contacts then).
  int buffer_overflows() const;
  // The contacts of the last step that involve a vehicle, each reported once per vehicle side.
  void vehicle_contacts(std::vector<VehicleContact>* out) const;
  // Back to the initial state (qpos0, zero velocities, time 0).
  void reset();

  // Names for events and queries, in a shard's model (ids as in VehicleContact and VehicleBinding).
  std::string body_name(int body_id, int shard = 0) const;
  std::string geom_name(int geom_id, int shard = 0) const;
  int body_id(const std::string& name) const;  // in shard 0; -1 if none

 private:
  explicit World(std::vector<std::unique_ptr<Shard>> shards, int threads);
  // the shard of a vehicle, and the vehicle's index in it
  Shard& shard_of(size_t vehicle) const;
  size_t local(size_t vehicle) const { return vehicle - first_[vehicles_[vehicle].shard]; }

  std::vector<std::unique_ptr<Shard>> shards_;
  std::vector<size_t> first_;  // per shard, its first vehicle's index in the world
  std::unique_ptr<StepPool> pool_;
  std::vector<VehicleBinding> vehicles_;
  std::vector<int> woken_;
  // per vehicle, parked or not: a mirror of the shards' parking, one byte each, so that the
  // simulation's per-step loops over every vehicle read it from one small array
  std::vector<char> parked_;
  // copies shard k's parking into parked_
  void sync_parked(size_t k);
};

}  // namespace uavsim::server::physics
