// Placing a vehicle program's camera frames: the telemetry kept with the time it was taken, moved
// on to a frame's stamp, and the frame's pinhole intrinsics in the vision library's terms.
#pragma once

#include <Eigen/Core>

#include "uavsim/client/camera.hpp"
#include "uavsim/vision/camera_model.hpp"

namespace uavsim::mission {

struct TimedPose {
  double time_s = -1.0;  // when it was taken, on the program's loop clock; negative: none yet
  Eigen::Vector3d position_enu_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d velocity_enu_m_s = Eigen::Vector3d::Zero();
  double yaw_enu_rad = 0.0;

  // the position at t_s, moved on from time_s by the velocity
  Eigen::Vector3d position_at(double t_s) const {
    return position_enu_m + velocity_enu_m_s * (t_s - time_s);
  }
};

inline vision::PinholeIntrinsics intrinsics_of(const client::CameraFrame& f) {
  vision::PinholeIntrinsics k;
  k.fx_px = f.intrinsics.fx;
  k.fy_px = f.intrinsics.fy;
  k.cx_px = f.intrinsics.cx;
  k.cy_px = f.intrinsics.cy;
  k.width_px = f.image.cols;
  k.height_px = f.image.rows;
  return k;
}

}  // namespace uavsim::mission
