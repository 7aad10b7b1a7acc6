// CameraDirector: the pose of a recording camera that follows the vehicles (uavsim-server
// --record-camera follow|follow:NAME|top). Pure: (sim time, vehicle positions) => camera pose.
//
//   follow  looks at the centre of the vehicles' bounding sphere from the south, 30 deg above the
//   horizon,
//           from the distance at which the sphere fills about 3/4 of the narrower field of view
//   top     looks straight down on that centre (north up), from the height at which the vehicles'
//           horizontal extent fits the frame
//
// The look-at point and the distance follow their targets through first-order filters in sim time,
// so the video does not jitter; the distance never drops below min_distance_m (a vehicle alone
// stays a vehicle, not a blur of pixels). A sim time earlier than the last one (reset) starts the
// filters afresh.
#pragma once

#include <Eigen/Core>
#include <optional>
#include <vector>

namespace uavsim::server::render {

enum class DirectorMode { kFollow, kTop };

struct DirectorParams {
  DirectorMode mode = DirectorMode::kFollow;
  std::optional<int> vehicle;   // only this vehicle's position counts; unset: all vehicles
  double fovy_deg = 45.0;       // the camera's vertical field of view
  double aspect = 4.0 / 3.0;    // width / height
  double min_distance_m = 8.0;  // never closer than this to the look-at point
  double max_distance_m = 400.0;
  double vehicle_radius_m =
      1.5;                      // added around every vehicle so that none touches the frame's edge
  double fill = 0.75;           // the fraction of the narrower field of view the vehicles span
  double elevation_deg = 30.0;  // follow: the view's angle above the horizon
  double look_at_tau_s = 0.8;   // filter time constants
  double distance_tau_s = 1.5;
};

// A camera pose: optical centre and the OpenCV camera frame (x right, y down, z forward) in ENU.
struct CameraPose {
  Eigen::Vector3d position_enu_m = Eigen::Vector3d::Zero();
  Eigen::Matrix3d R_enu_cam = Eigen::Matrix3d::Identity();
};

class CameraDirector {
 public:
  explicit CameraDirector(const DirectorParams& params) : params_(params) {}

  // The pose at sim time t_s for the vehicles at positions_enu_m (vehicle order). Vehicles missing
  // from the list (or no vehicles) keep the last look-at point. One thread at a time (the render
  // thread).
  CameraPose aim(double t_s, const std::vector<Eigen::Vector3d>& positions_enu_m);

  const DirectorParams& params() const { return params_; }

 private:
  DirectorParams params_;
  std::optional<double> last_t_s_;
  Eigen::Vector3d look_at_enu_m_ = Eigen::Vector3d::Zero();
  double distance_m_ = 0.0;
};

// The rotation of a camera at `from` looking at `to` (OpenCV frame in ENU, image up = world up, or
// north when looking straight down).
Eigen::Matrix3d look_at_rotation(const Eigen::Vector3d& from_enu_m,
                                 const Eigen::Vector3d& to_enu_m);

}  // namespace uavsim::server::render
