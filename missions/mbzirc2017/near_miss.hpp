// Near misses of the MBZIRC 2017 landing, scored by the launcher from the sim API's ground truth
// (never seen by the UAV program): the smallest clearance between the UAV's colliding geoms and the
// truck's parts other than the deck (the cab above all), and the margin of the skids to the deck's
// edges while they are at the deck's height. Shapes come from the models' MJCF (the truck object
// and the vehicle template), so a lucky landing is told apart from a safe one with the geometry the
// simulator collides.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "uavsim/vision/eight_track.hpp"

namespace uavsim::missions::mbzirc2017 {

// An axis-aligned box in its body's frame (the truck's geoms are not rotated).
struct BodyBox {
  std::string name;
  Eigen::Vector3d centre_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d half_m = Eigen::Vector3d::Zero();
};

// The truck's colliding geoms: the deck (names starting "deck", the landing surface) and the rest.
struct TruckShape {
  BodyBox deck;
  std::vector<BodyBox> parts;  // every other colliding geom (cab, chassis)
};

// The vehicle's colliding geoms as spheres in its body frame: cylinders (hull, propeller discs) by
// points on their rims and centres, capsules (skids) by points along their axes with their radius.
// Points on a rim of radius r sampled every 2 pi / 24 are within r (1 - cos(pi / 24)) = 0.0086 r of
// the true rim.
struct VehicleShape {
  struct Sphere {
    Eigen::Vector3d centre_m;
    double radius_m;
  };
  std::vector<Sphere> spheres;
  std::vector<Eigen::Vector3d> gear_points_m;  // the skids' ends (lowest colliding capsules)
};

// Loads the first body of an MJCF file's worldbody: its colliding geoms (contype or conaffinity
// not 0, after default classes and the body's childclass). Config errors (missing file, geom types
// or rotations this scoring does not handle, a nested body) throw std::runtime_error naming the
// file and the geom.
TruckShape load_truck_shape(const std::string& mjcf_path);
VehicleShape load_vehicle_shape(const std::string& mjcf_path);

// Signed distance from a point to a box (negative inside).
double box_distance_m(const BodyBox& box, const Eigen::Vector3d& p_m);

// Where on the eight an arc length is: "crossing" (within crossing_half_m of either crossing),
// "straight" or "curve".
std::string eight_part(const vision::EightTrack& track, double s_m, double crossing_half_m = 5.0);

// The running minima over a run's samples. Not thread-safe.
class NearMissTracker {
 public:
  NearMissTracker(TruckShape truck, VehicleShape vehicle);

  // One ground-truth sample: the vehicle's body origin and attitude, the truck's origin and yaw.
  // Between two samples the vehicle's pose relative to the truck is interpolated (substeps).
  void add(const Eigen::Vector3d& vehicle_enu_m, const Eigen::Quaterniond& q_enu_body,
           const Eigen::Vector3d& truck_enu_m, double truck_yaw_rad);

  // The smallest clearance to each part but the deck, by name (0 or less: contact); empty before
  // the first sample. The chassis lies under the deck (0.1 m below its top): a UAV on the deck is
  // that far from it.
  const std::map<std::string, double>& min_clearance_m() const { return min_part_m_; }
  std::optional<double> min_clearance_m(const std::string& part) const;
  // The smallest margin of the skids' ends to the deck's edges (negative: over the edge) while the
  // lowest of them was within kAtDeck_m of the deck's top and the body origin over the deck (within
  // its half extents plus kOverDeck_m); unset if it never was.
  std::optional<double> min_deck_edge_margin_m() const { return min_deck_edge_m_; }

  // The latest sample: the body origin in the truck's frame (x forward, from the marker's centre
  // on the ground) and the skids' height above the deck's top; unset before the first sample.
  struct Relative {
    Eigen::Vector3d p_truck_m;
    double skid_height_m;
  };
  std::optional<Relative> latest() const { return latest_; }

  static constexpr double kAtDeck_m = 0.05;
  static constexpr double kOverDeck_m = 0.5;
  static constexpr int kSubsteps = 5;

 private:
  void score(const Eigen::Vector3d& p_truck_m, const Eigen::Quaterniond& q_truck_body);

  TruckShape truck_;
  VehicleShape vehicle_;
  std::optional<std::pair<Eigen::Vector3d, Eigen::Quaterniond>> last_;  // relative pose
  std::map<std::string, double> min_part_m_;
  std::optional<double> min_deck_edge_m_;
  std::optional<Relative> latest_;
};

}  // namespace uavsim::missions::mbzirc2017
