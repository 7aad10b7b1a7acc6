// Landing-marker detector for MBZIRC 2017 Challenge 1 (seed 7.1): a white ring with a cross inside
// on a dark 1.5 x 1.5 m square, seen by a down-looking camera. Candidates are white blobs whose
// outline is an ellipse and whose inside is partly dark (the ring's hole); each is refined with the
// Circle Hough Transform (seed fig. 7.4). Pixel -> arena coordinates via camera_model.hpp's
// pixel_to_plane_enu.
//
// The seed tracked the marker with OpenTLD first; a frame-by-frame detector is enough in
// simulation.
#pragma once

#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <optional>
#include <vector>

#include "uavsim/vision/camera_model.hpp"

namespace uavsim::vision {

// The marker's geometry. Defaults: our model of the MBZIRC 2017 target (1.5 m square, fig. 7.1b);
// the server's truck deck texture is built from these numbers.
struct LandingMarkerGeometry {
  double square_side_m = 1.5;
  double ring_outer_radius_m = 0.65;
  double ring_inner_radius_m = 0.50;
  double cross_half_length_m = 0.35;  // the cross does not touch the ring
  double cross_half_width_m = 0.06;
};

struct MarkerDetectorParams {
  LandingMarkerGeometry geometry;
  double min_radius_px = 8.0;
  double max_ellipse_residual = 0.08;  // rms distance of the outline from its ellipse / radius
  double max_axis_ratio = 2.0;  // major / minor axis: oblique views beyond ~60 deg are rejected
  // white share of the ring's outline: ring plus cross, pi (0.65^2 - 0.5^2) = 0.542 m^2 plus
  // 2 * 0.7 * 0.12 - 0.12^2 = 0.154 m^2, over pi 0.65^2 = 1.327 m^2: 0.52
  double min_white_fraction = 0.30;
  double max_white_fraction = 0.75;
  bool hough_refine = true;
  // second threshold level as a share of Otsu's (0 or 1 = Otsu's only), see detect(): paint greyed
  // by shade (or a renderer's shadow acne) next to a bright truck body falls below Otsu's split
  double low_threshold_share = 0.5;
};

struct MarkerDetection {
  cv::Point2d centre_px;        // the ring's centre
  double radius_px = 0.0;       // the ring's outer radius (geometric mean of the ellipse axes)
  double white_fraction = 0.0;  // see MarkerDetectorParams
  bool hough_refined = false;
};

// Detector with reusable work buffers. One instance per camera thread; detect() is not thread-safe.
class MarkerDetector {
 public:
  explicit MarkerDetector(const MarkerDetectorParams& params = {});

  // Detects the landing marker in a grey (CV_8UC1) or BGR (CV_8UC3) frame; the best candidate (the
  // largest) or nullopt.
  std::optional<MarkerDetection> detect(const cv::Mat& image);

  // Every candidate of the last detect() call, largest first.
  const std::vector<MarkerDetection>& candidates() const { return candidates_; }

 private:
  // thresholds a grey image at each level and collects its candidates
  void search_levels(const cv::Mat& gray);
  // appends the ring candidates of one binary image (white = paint) to candidates_
  void find_candidates(const cv::Mat& binary);

  MarkerDetectorParams params_;
  cv::Mat gray_;
  cv::Mat binary_;
  cv::Mat disc_;
  std::vector<MarkerDetection> candidates_;
};

// The marker's centre on the plane z_enu = deck_height_enu_m, from a detection and the camera pose
// at the image's timestamp; nullopt if the ray misses the plane.
std::optional<Eigen::Vector3d> marker_position_enu(const MarkerDetection& detection,
                                                   const PinholeIntrinsics& intrinsics,
                                                   const CameraPose& pose,
                                                   double deck_height_enu_m);

}  // namespace uavsim::vision
