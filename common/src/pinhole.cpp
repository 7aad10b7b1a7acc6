#include "uavsim/common/pinhole.hpp"

#include <cmath>

#include "uavsim/common/angles.hpp"

namespace uavsim::common {
namespace {

PinholeIntrinsics centred(int width_px, int height_px, double fy_px) {
  PinholeIntrinsics k;
  k.width_px = width_px;
  k.height_px = height_px;
  k.fy_px = fy_px;
  k.fx_px = fy_px;
  k.cx_px = 0.5 * (width_px - 1);
  k.cy_px = 0.5 * (height_px - 1);
  return k;
}

}  // namespace

PinholeIntrinsics PinholeIntrinsics::from_fovy(int width_px, int height_px, double fovy_rad) {
  return centred(width_px, height_px, 0.5 * height_px / std::tan(0.5 * fovy_rad));
}

PinholeIntrinsics PinholeIntrinsics::from_fovy_deg(int width_px, int height_px, double fovy_deg) {
  return centred(width_px, height_px, 0.5 * height_px / std::tan(0.5 * fovy_deg * kPi / 180.0));
}

double PinholeIntrinsics::fovy_deg_of(int height_px, double fy_px) {
  return 2.0 * std::atan(0.5 * height_px / fy_px) * 180.0 / kPi;
}

Eigen::Vector2d PinholeIntrinsics::project(const Eigen::Vector3d& p_cam_m) const {
  return {fx_px * p_cam_m.x() / p_cam_m.z() + cx_px, fy_px * p_cam_m.y() / p_cam_m.z() + cy_px};
}

Eigen::Vector3d PinholeIntrinsics::ray_cam(const Eigen::Vector2d& pixel_px) const {
  return Eigen::Vector3d((pixel_px.x() - cx_px) / fx_px, (pixel_px.y() - cy_px) / fy_px, 1.0)
      .normalized();
}

bool PinholeIntrinsics::contains(const Eigen::Vector2d& pixel_px) const {
  return pixel_px.x() >= -0.5 && pixel_px.y() >= -0.5 && pixel_px.x() < width_px - 0.5 &&
         pixel_px.y() < height_px - 0.5;
}

}  // namespace uavsim::common
