#include "render/camera_director.hpp"
#include "uavsim/common/angles.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

namespace uavsim::server::render {

namespace {
using common::kPi;
}  // namespace

Eigen::Matrix3d look_at_rotation(const Eigen::Vector3d& from_enu_m,
                                 const Eigen::Vector3d& to_enu_m) {
  // z forward; x right = forward x up (east when looking straight down); y down = z x x
  Eigen::Vector3d z = to_enu_m - from_enu_m;
  if (z.norm() < 1e-9) z = -Eigen::Vector3d::UnitZ();
  z.normalize();
  Eigen::Vector3d x = z.cross(Eigen::Vector3d::UnitZ());
  if (x.norm() < 1e-6) x = Eigen::Vector3d::UnitX();
  x.normalize();
  const Eigen::Vector3d y = z.cross(x);
  Eigen::Matrix3d R;
  R.col(0) = x;
  R.col(1) = y;
  R.col(2) = z;
  return R;
}

CameraPose CameraDirector::aim(double t_s, const std::vector<Eigen::Vector3d>& positions_enu_m) {
  const DirectorParams& p = params_;
  // the vehicles that count
  std::vector<Eigen::Vector3d> pts;
  if (p.vehicle) {
    if (*p.vehicle >= 0 && static_cast<size_t>(*p.vehicle) < positions_enu_m.size()) {
      pts.push_back(positions_enu_m[static_cast<size_t>(*p.vehicle)]);
    }
  } else {
    for (const Eigen::Vector3d& v : positions_enu_m) {
      if (v.allFinite()) pts.push_back(v);
    }
  }

  // target look-at point and distance: the centre of their bounding box and the distance at which
  // their bounding sphere (plus a vehicle's radius) spans `fill` of the narrower field of view
  std::optional<Eigen::Vector3d> target;
  double target_distance_m = p.min_distance_m;
  if (!pts.empty()) {
    Eigen::Vector3d lo = pts[0], hi = pts[0];
    for (const Eigen::Vector3d& v : pts) {
      lo = lo.cwiseMin(v);
      hi = hi.cwiseMax(v);
    }
    target = 0.5 * (lo + hi);
    const double half_fovy = 0.5 * p.fovy_deg * kPi / 180.0;
    const double half_fovx = std::atan(std::tan(half_fovy) * p.aspect);
    const double half_fov = std::min(half_fovx, half_fovy) * p.fill;
    double radius_m = 0.0;
    for (const Eigen::Vector3d& v : pts) {
      const Eigen::Vector3d d = v - *target;
      radius_m = std::max(radius_m, p.mode == DirectorMode::kTop ? d.head<2>().norm() : d.norm());
    }
    radius_m += p.vehicle_radius_m;
    target_distance_m = radius_m / std::sin(half_fov);
    if (p.mode == DirectorMode::kTop)
      target_distance_m += hi.z() - target->z();  // above the highest one
    target_distance_m = std::clamp(target_distance_m, p.min_distance_m, p.max_distance_m);
  }

  // first-order filters in sim time; the first call (or a reset) jumps to the target
  const bool restart = !last_t_s_ || t_s < *last_t_s_;
  if (restart) {
    look_at_enu_m_ = target.value_or(Eigen::Vector3d::Zero());
    distance_m_ = target_distance_m;
  } else {
    const double dt_s = t_s - *last_t_s_;
    const double a_look = 1.0 - std::exp(-dt_s / std::max(1e-6, p.look_at_tau_s));
    const double a_dist = 1.0 - std::exp(-dt_s / std::max(1e-6, p.distance_tau_s));
    if (target) look_at_enu_m_ += a_look * (*target - look_at_enu_m_);
    distance_m_ += a_dist * (target_distance_m - distance_m_);
    // zooming out must keep up with vehicles that spread fast: never narrower than the target
    distance_m_ = std::max(distance_m_, std::min(target_distance_m, p.max_distance_m) * 0.8);
  }
  distance_m_ = std::max(distance_m_, p.min_distance_m);
  last_t_s_ = t_s;

  // the pose: from the south and above (follow) or straight above (top)
  Eigen::Vector3d offset;
  if (p.mode == DirectorMode::kTop) {
    offset = Eigen::Vector3d::UnitZ();
  } else {
    const double el = p.elevation_deg * kPi / 180.0;
    offset = Eigen::Vector3d(0.0, -std::cos(el), std::sin(el));
  }
  CameraPose pose;
  pose.position_enu_m = look_at_enu_m_ + distance_m_ * offset;
  pose.position_enu_m.z() = std::max(pose.position_enu_m.z(), 0.5);  // never under the ground
  pose.R_enu_cam = look_at_rotation(pose.position_enu_m, look_at_enu_m_);
  return pose;
}

}  // namespace uavsim::server::render
