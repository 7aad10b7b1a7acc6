// Test helpers for rendered RGB8 frames: where the pixels of one colour lie, and where a world
// point projects through a frame's pose and intrinsics.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>

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

// How far apart two RGB8 frames of one size are: the mean absolute difference over every pixel and
// channel (grey levels), and the fraction of pixels with some channel off by more than
// `large_diff`.
struct FrameDifference {
  double mean_abs_diff = 0.0;
  double large_fraction = 0.0;
  size_t large_pixels = 0;
};
inline FrameDifference frame_difference(const CameraFrame& a, const CameraFrame& b,
                                        int large_diff) {
  FrameDifference d;
  double abs_sum = 0.0;
  const size_t pixels = a.pixels.size() / 3;
  for (size_t i = 0; i < pixels; ++i) {
    int worst = 0;
    for (int c = 0; c < 3; ++c) {
      const int diff = std::abs(int{a.pixels[3 * i + c]} - int{b.pixels[3 * i + c]});
      abs_sum += diff;
      worst = std::max(worst, diff);
    }
    if (worst > large_diff) ++d.large_pixels;
  }
  if (pixels > 0) {
    d.mean_abs_diff = abs_sum / static_cast<double>(a.pixels.size());
    d.large_fraction = static_cast<double>(d.large_pixels) / static_cast<double>(pixels);
  }
  return d;
}

// the world point in OpenCV pixels, through the frame's pose and intrinsics
inline Eigen::Vector2d project(const CameraFrame& f, const Eigen::Vector3d& p_enu) {
  const Eigen::Vector3d x = f.R_enu_cam.transpose() * (p_enu - f.position_enu_m);
  const CameraIntrinsics& k = f.intrinsics;
  return {k.fx_px * x.x() / x.z() + k.cx_px, k.fy_px * x.y() / x.z() + k.cy_px};
}

}  // namespace uavsim::server::render::testing
