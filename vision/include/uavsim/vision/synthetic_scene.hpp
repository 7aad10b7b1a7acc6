// Synthetic camera frames for tests and benchmarks, until the server's renderer feeds real ones: a
// shaded sphere (a balloon) over a sky/sand background, green clutter, and the landing marker on a
// ground plane seen through a homography. Deterministic for a given seed. Thread-safe (no shared
// state).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <opencv2/core.hpp>

#include "uavsim/vision/camera_model.hpp"
#include "uavsim/vision/marker_detector.hpp"

namespace uavsim::vision::synthetic {

// Forward-looking background: sky-blue gradient above the horizon row, sand texture below.
cv::Mat sky_sand_background(const PinholeIntrinsics& intrinsics, double horizon_row_px,
                            uint64_t seed);

// Down-looking background: a sand texture.
cv::Mat sand_background(const PinholeIntrinsics& intrinsics, uint64_t seed);

// Renders a Lambert-shaded sphere of a BGR albedo centred at centre_cam_m, lit from light_dir_cam
// (unit, pointing towards the light; the sun above a forward camera is (0, -1, 0)), anti-aliased by
// 4x4 supersampling.
void render_sphere(const PinholeIntrinsics& intrinsics, const Eigen::Vector3d& centre_cam_m,
                   double diameter_m, const cv::Scalar& albedo_bgr,
                   const Eigen::Vector3d& light_dir_cam, cv::Mat* image_bgr);

// Paints non-round green clutter (a bush-like blob, a green board, a thin pole) at random places.
void render_green_clutter(uint64_t seed, cv::Mat* image_bgr);

// Renders the marker lying on the plane z_enu = deck_height_enu_m with its centre at
// marker_centre_enu_m (x, y) and its sides rotated by marker_yaw_rad, seen from pose, over the
// given image.
void render_marker(const PinholeIntrinsics& intrinsics, const CameraPose& pose,
                   const LandingMarkerGeometry& geometry,
                   const Eigen::Vector2d& marker_centre_enu_m, double marker_yaw_rad,
                   double deck_height_enu_m, cv::Mat* image_bgr);

// Adds Gaussian pixel noise of sigma (grey levels), seeded.
void add_noise(double sigma, uint64_t seed, cv::Mat* image);

}  // namespace uavsim::vision::synthetic
