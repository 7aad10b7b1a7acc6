// The MBZIRC 2017 target truck (seed 7.1): a kinematic (mocap) body that drives the eight-shaped track at
// 15 km/h for the first 8 minutes of sim time and 5 km/h after, carrying a 1.5 x 1.5 m landing marker on
// a flat deck. A vehicle whose landing gear touches the deck slower than 1 m/s relative to it has landed:
// the truck records landed_on_target and carries it (its pose is set relative to the deck every step)
// until its rotors lift more than its weight. Gear contact with the deck is never a crash; any other
// vehicle contact with the truck is left to the default (a crash).
//
// World file (models/objects/truck.xml; parameters as custom numerics named after the instance):
//   <uavsim_object type="truck" name="truck"/>
//   <numeric name="uavsim:truck:track" data="R_m D_m centre_x_m centre_y_m yaw_deg"/>   any prefix
//   <numeric name="uavsim:truck:speed" data="speed1_kmh speed2_kmh switch_time_s start_s_m"/>  any prefix
//   <numeric name="uavsim:truck:driver" data="lateral_amplitude_m speed_wobble_fraction"/>  (truck_driver.hpp)
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "objects/eight_track.hpp"
#include "objects/truck_driver.hpp"
#include "sim/simulation.hpp"

namespace uavsim::server::objects {

struct TruckParams {
  std::string name = "truck";
  EightTrackParams track;
  SpeedProfile speed;
  DriverParams driver;  // off by default: the ideal track at the scheduled speed
  double landing_speed_m_s = 1.0;  // relative speed below which a gear touchdown on the deck is a landing
};

// The truck's ground truth.
struct TruckState {
  std::string name;
  double s_m = 0.0;          // arc length along the track, wrapped (of the point the driver follows)
  int laps = 0;              // completed laps
  double speed_m_s = 0.0;
  Eigen::Vector3d position_enu_m = Eigen::Vector3d::Zero();  // the body origin (on the ground)
  Eigen::Vector3d velocity_enu_m_s = Eigen::Vector3d::Zero();
  double yaw_rad = 0.0;      // heading, from east counter-clockwise
  Eigen::Vector3d deck_centre_enu_m = Eigen::Vector3d::Zero();  // the marker's centre on the deck top
  std::vector<int> carried_vehicles;
};

class Truck : public sim::WorldObject {
 public:
  // Binds to the truck's mocap body and deck geom in sim's world. Throws physics::WorldError naming the
  // body or parameter if the world does not have them. Loop thread (or before the loop starts).
  Truck(sim::Simulation& sim, const TruckParams& params);

  void before_step(sim::Simulation& sim) override;
  bool on_contact(sim::Simulation& sim, const physics::VehicleContact& contact) override;
  void reset(uint64_t seed) override;

  // The truck now. Loop thread only.
  TruckState state(double time_s) const;
  const EightTrack& track() const { return track_; }
  const TruckParams& params() const { return params_; }
  const TruckDriver& driver() const { return driver_; }
  double deck_height_m() const { return deck_top_m_; }

 private:
  struct Carried {
    int vehicle = -1;
    Eigen::Vector3d p_truck_m;    // vehicle origin in the truck frame
    Eigen::Quaterniond q_truck_body;
  };
  // pose and velocities of the truck frame at time t
  void pose_at(double time_s, Eigen::Vector3d* p, Eigen::Quaterniond* q, Eigen::Vector3d* v,
               double* yaw_rate_rad_s) const;

  TruckParams params_;
  EightTrack track_;
  TruckDriver driver_;  // redrawn from the seed on reset
  int body_id_ = -1;
  std::vector<int> deck_geoms_;
  double deck_top_m_ = 1.5;  // deck top above the body origin
  std::vector<Carried> carried_;
};

}  // namespace uavsim::server::objects
