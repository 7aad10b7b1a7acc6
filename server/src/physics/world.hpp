// The MuJoCo side of the simulation: a loaded world, the vehicles found in it, rotor wrenches written into
// qfrc_applied, ground truth and contacts. The only module (with render/) that includes MuJoCo; this header
// forward-declares MuJoCo's structs so users of World do not see mujoco.h.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "airframe/airframe.hpp"
#include "fc/fc_types.hpp"
#include "physics/world_composer.hpp"

struct mjModel_;
struct mjData_;

namespace uavsim::server::physics {

// A vehicle found in the world (models/README.md: <text name="uavsim:vehicle:BODY" data="FRAME"/>).
struct VehicleBinding {
  std::string name;  // the body name, e.g. "uav0"
  int body_id = -1;
  int qpos_adr = -1;  // the free joint's 7 qpos
  int dof_adr = -1;   // the free joint's 6 dofs
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
};

class World {
 public:
  // Composes and loads a world file. Throws WorldError naming the file (and line) on any error.
  static std::unique_ptr<World> load(const std::string& world_path, const ComposeOptions& options);
  // Loads standalone MJCF text (label names it in errors). Throws WorldError.
  static std::unique_ptr<World> from_mjcf(const std::string& mjcf, const std::string& label);
  ~World();
  World(const World&) = delete;
  World& operator=(const World&) = delete;

  const mjModel_* model() const { return m_; }
  // For run-time model switches (a popped balloon's geoms, physics/object_bodies). Loop thread only.
  mjModel_* mutable_model() { return m_; }
  mjData_* data() { return d_; }
  const mjData_* data() const { return d_; }

  const std::vector<VehicleBinding>& vehicles() const { return vehicles_; }
  // A vehicle's airframe, for conditions set before the simulation starts (battery sag). Loop thread only.
  airframe::AirframeParams& mutable_airframe(size_t vehicle) { return vehicles_[vehicle].airframe; }
  double time_s() const;
  double timestep_s() const;
  void set_timestep_s(double dt_s);

  // Ground truth of a vehicle's free body (position and velocity of the body origin).
  fc::TruthState truth(size_t vehicle) const;
  // Writes a vehicle's wrench about its body origin into its free joint's qfrc_applied dofs:
  // world-frame force in dofs 0-2, body-frame torque in dofs 3-5.
  void apply_wrench(size_t vehicle, const airframe::Wrench& wrench);
  // Places a vehicle (teleport) at rest; used by resets and crash handling in tests.
  void set_pose(size_t vehicle, const double pos_enu_m[3], const double quat_wxyz[4]);

  // Advances physics by one timestep (mj_step; when every dof belongs to a parked vehicle and nothing
  // is kinematic, only the clock advances). Parked vehicles are then put back where they are held;
  // one that something touched wakes instead.
  void step();

  // Parking: a vehicle at rest on static geometry is held exactly where it is (qpos fixed, qvel zero)
  // and its geoms stop touching static geometry (no contact constraints: a grounded quad's resting
  // contacts are most of its step), while moving bodies (awake vehicles, kinematic objects) still
  // collide with it and wake it. truth() of a parked vehicle is that pose at rest (zero velocity and
  // acceleration). Loop thread only.
  bool parked(size_t vehicle) const { return parked_[vehicle].on; }
  size_t parked_count() const { return parked_count_; }
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

  // Names for events and queries.
  std::string body_name(int body_id) const;
  std::string geom_name(int geom_id) const;
  int body_id(const std::string& name) const;  // -1 if none

 private:
  World(mjModel_* m, mjData_* d, const std::string& label);
  void find_vehicles(const std::string& label);

  void init_parking();
  void hold_parked();
  void set_parked_bits(size_t vehicle, bool parked);

  struct Parking {
    bool on = false;
    double qpos[7] = {};
    std::vector<int> geoms;  // the vehicle's collidable geoms
  };

  mjModel_* m_ = nullptr;
  mjData_* d_ = nullptr;
  std::vector<VehicleBinding> vehicles_;
  std::vector<int> body_vehicle_;   // body id -> vehicle index or -1 (via the root body)
  std::vector<char> geom_is_gear_;  // geom id -> landing gear
  std::vector<char> body_static_;   // body id -> cannot move (welded to the world, not kinematic)
  std::vector<int> geom_contype0_, geom_conaffinity0_;  // awake collision bits
  std::vector<Parking> parked_;
  size_t parked_count_ = 0;
  bool forwarded_ = false;  // kinematics are current for the clock-only step
  std::vector<int> woken_;
};

}  // namespace uavsim::server::physics
