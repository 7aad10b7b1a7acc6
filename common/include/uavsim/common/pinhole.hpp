// The one pinhole camera model: the renderer states the intrinsics of what it draws with it, and
// the vision library projects and back-projects with the same numbers (a second copy could drift,
// e.g. in the pixel-centre convention, and every detection would be off by half a pixel without a
// test noticing).
//
// OpenCV's convention: pixel (u, v) has its centre at integer coordinates, u to the right, v down,
// (0, 0) the centre of the top-left pixel; a point X_cam (x right, y down, z forward) projects to
// u = fx * X/Z + cx, v = fy * Y/Z + cy. No distortion: the simulator renders an ideal pinhole.
#pragma once

#include <Eigen/Core>

namespace uavsim::common {

struct PinholeIntrinsics {
  double fx_px = 0.0;
  double fy_px = 0.0;
  double cx_px = 0.0;
  double cy_px = 0.0;
  int width_px = 0;
  int height_px = 0;

  // A centred camera with square pixels from its vertical field of view, as MuJoCo's <camera fovy>
  // defines it: the frustum spans the image height, h/2 pixels either side of the axis, at
  // tan(fovy/2), so fy = (h/2) / tan(fovy/2), fx = fy, and the axis falls between the middle
  // pixels, cx = (w-1)/2, cy = (h-1)/2 (OpenGL samples pixel centres at half-integers). The degree
  // form is what a world file and the camera options state; it keeps its own arithmetic (degrees to
  // radians inside the tangent's argument) so the intrinsics a frame carries are the same to the
  // bit as before the two copies merged.
  static PinholeIntrinsics from_fovy(int width_px, int height_px, double fovy_rad);
  static PinholeIntrinsics from_fovy_deg(int width_px, int height_px, double fovy_deg);

  // The inverse: the vertical field of view, in degrees, of an image height_px rows high with the
  // focal length fy_px, fovy = 2 atan((h/2) / fy) (for a camera that frames what another draws).
  static double fovy_deg_of(int height_px, double fy_px);

  // Projects a point in the camera frame to pixels. Precondition: p_cam_m.z() > 0.
  Eigen::Vector2d project(const Eigen::Vector3d& p_cam_m) const;

  // Unit ray in the camera frame through a pixel.
  Eigen::Vector3d ray_cam(const Eigen::Vector2d& pixel_px) const;

  // Whether a pixel position lies on the image (pixel areas reach half a pixel past the centres).
  bool contains(const Eigen::Vector2d& pixel_px) const;
};

}  // namespace uavsim::common
