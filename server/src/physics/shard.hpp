// One physics shard (physics/world.hpp): an mjModel + mjData holding some of the world's vehicles
// and the whole static scene, with the parking of its own vehicles. Vehicle indices here are the
// shard's own (0 .. vehicles().size()); World maps them to the world's. Internal to physics/: only
// World uses it. A Shard is stepped by one thread at a time; different shards share nothing and
// step concurrently.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "physics/world.hpp"

namespace uavsim::server::physics {

class Shard {
 public:
  // Loads standalone MJCF text (label names it in errors). Throws WorldError.
  static std::unique_ptr<Shard> from_mjcf(const std::string& mjcf, const std::string& label);
  ~Shard();
  Shard(const Shard&) = delete;
  Shard& operator=(const Shard&) = delete;

  mjModel_* model() const { return m_; }
  mjData_* data() const { return d_; }
  const std::vector<VehicleBinding>& vehicles() const { return vehicles_; }
  double time_s() const;
  double timestep_s() const;
  void set_timestep_s(double dt_s);

  // World's functions of the same names, for the shard's own vehicles.
  airframe::TruthState truth(size_t vehicle) const;
  void apply_wrench(size_t vehicle, const airframe::Wrench& wrench);
  void set_pose(size_t vehicle, const double pos_enu_m[3], const double quat_wxyz[4]);
  void step();
  bool parked(size_t vehicle) const { return parked_[vehicle].on; }
  size_t parked_count() const { return parked_count_; }
  void park(size_t vehicle);
  void wake(size_t vehicle);
  void park_resting();
  const std::vector<int>& woken_by_contact() const { return woken_; }
  int buffer_overflows() const;
  // Appends the last step's vehicle contacts, the vehicle indices offset by first_vehicle (the
  // shard's first vehicle in the world) and stamped with the shard's index.
  void vehicle_contacts(int shard, int first_vehicle, std::vector<VehicleContact>* out) const;
  void reset();
  std::string body_name(int body_id) const;
  std::string geom_name(int geom_id) const;
  bool vehicle_visual_only(int geom_id) const;
  int body_id(const std::string& name) const;

 private:
  Shard(mjModel_* m, mjData_* d, const std::string& label);
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
