// Test helpers for rendered RGB8 frames: where the pixels of one colour lie, and where a world
// point projects through a frame's pose and intrinsics.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <cstddef>
#include <cstdint>

#include "render/camera_renderer.hpp"
#include "uavsim/common/angles.hpp"

namespace uavsim::server::render::testing {

// the pixels a predicate picks: centroid and the radius of the disc of equal area
struct Blob {
  double u = 0.0;
  double v = 0.0;
  double area_px = 0.0;
  double radius_px() const { return std::sqrt(area_px / common::kPi); }
};

// pick(r, g, b) -> bool over every pixel of an RGB8 frame
template <typename Pick>
Blob find_blob(const CameraFrame& f, Pick pick) {
  Blob b;
  for (int v = 0; v < f.height_px; ++v) {
    for (int u = 0; u < f.width_px; ++u) {
      const uint8_t* p = f.pixels.data() + (static_cast<size_t>(v) * f.width_px + u) * 3;
      if (!pick(int{p[0]}, int{p[1]}, int{p[2]})) continue;
      b.u += u;
      b.v += v;
      b.area_px += 1.0;
    }
  }
  if (b.area_px > 0) {
    b.u /= b.area_px;
    b.v /= b.area_px;
  }
  return b;
}

// the world point in OpenCV pixels, through the frame's pose and intrinsics
inline Eigen::Vector2d project(const CameraFrame& f, const Eigen::Vector3d& p_enu) {
  const Eigen::Vector3d x = f.R_enu_cam.transpose() * (p_enu - f.position_enu_m);
  const CameraIntrinsics& k = f.intrinsics;
  return {k.fx_px * x.x() / x.z() + k.cx_px, k.fy_px * x.y() / x.z() + k.cy_px};
}

}  // namespace uavsim::server::render::testing
