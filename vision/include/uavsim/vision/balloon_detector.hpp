// Green-balloon detector for MBZIRC 2020 Challenge 1 (seed 7.2): a colour filter, then round blobs,
// refined with the Circle Hough Transform; 3D position in the camera frame from the known balloon
// diameter; a temporal filter against false positives (N consecutive hits) and a low-pass filter.
//
// The seed used LINE templates before the colour filter; a colour filter plus shape tests is enough
// for the simulator's flat-coloured balloons and is cheaper.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <opencv2/core.hpp>
#include <vector>

#include "uavsim/vision/camera_model.hpp"

namespace uavsim::vision {

struct BalloonDetectorParams {
  // Balloon diameter. Default: 0.6 m, our balloon model (MBZIRC 2020 used party balloons of about
  // this size); the server's models/objects/balloon.xml must agree.
  double balloon_diameter_m = 0.6;

  // HSV window (OpenCV scales: hue 0..180, saturation and value 0..255). Green is hue 60. Shading
  // from the sun above darkens the lower half but keeps hue and saturation, so value_min is low;
  // sky blue (hue ~105) and sand (hue ~20, low saturation) stay outside.
  int hue_min = 38;
  int hue_max = 85;
  int saturation_min = 70;
  int value_min = 25;

  // Shape tests on each blob of the mask.
  double min_radius_px = 4.0;
  double max_radius_px = 2000.0;
  double min_fill_ratio = 0.70;    // blob area / fitted circle area: rejects crescents and stripes
  double max_fit_residual = 0.10;  // rms radial residual / radius: rejects polygons and bushes
  double max_circle_outside =
      0.10;  // share of the fitted circle outside the image: rejects cut blobs

  // Circle Hough Transform refinement of each candidate (seed fig. 7.12).
  bool hough_refine = true;
  int max_detections = 8;
};

// One balloon seen in one frame.
struct BalloonDetection {
  cv::Point2d centre_px;
  double radius_px = 0.0;
  Eigen::Vector3d position_cam_m = Eigen::Vector3d::Zero();  // the balloon's centre
  double range_m = 0.0;                                      // |position_cam_m|
  double fit_residual =
      0.0;  // rms radial residual / radius of the contour fit (0 = perfect circle)
  bool hough_refined = false;
};

// Balloon-centre position in the camera frame from its image circle and true diameter: the circle's
// rim rays form a cone around the centre ray whose half-angle a satisfies sin(a) = radius / range.
Eigen::Vector3d sphere_position_from_circle(const PinholeIntrinsics& intrinsics,
                                            const cv::Point2d& centre_px, double radius_px,
                                            double diameter_m);

// Detector with reusable work buffers. One instance per camera thread; detect() is not thread-safe.
class BalloonDetector {
 public:
  BalloonDetector(const BalloonDetectorParams& params, const PinholeIntrinsics& intrinsics);

  // Detects green balloons in a BGR frame (CV_8UC3) of the intrinsics' size, largest first.
  std::vector<BalloonDetection> detect(const cv::Mat& bgr);

  // The colour mask of the last detect() call, for tuning (seed 6.4) and tests.
  const cv::Mat& mask() const { return mask_; }

  const BalloonDetectorParams& params() const { return params_; }

 private:
  BalloonDetectorParams params_;
  PinholeIntrinsics intrinsics_;
  cv::Mat hsv_;
  cv::Mat mask_;
  cv::Mat work_;
};

struct BalloonTrackerParams {
  int confirm_hits = 3;        // consecutive frames with a hit before a track is reported
  int max_misses = 3;          // consecutive frames without a hit before a track is dropped
  double gate_m = 1.5;         // a detection further than this from a track starts a new track
  double lowpass_tau_s = 0.3;  // time constant of the first-order low-pass on position
};

// A balloon followed over frames.
struct BalloonTrack {
  int id = 0;
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();  // low-passed, in the caller's frame
  int hits = 0;                                          // consecutive hits
  int misses = 0;                                        // consecutive misses
  int64_t last_hit_stamp_us = 0;
  bool confirmed = false;  // hits reached confirm_hits at least once
};

// Temporal filter on balloon positions (seed 7.2: "a temporal filter discarded false positives and
// a low-pass filter reduced the noise"). Positions can be in any frame, but a world frame (ENU)
// keeps still balloons still while the UAV moves. Not thread-safe.
class BalloonTracker {
 public:
  explicit BalloonTracker(const BalloonTrackerParams& params = {});

  // Associates one frame's positions (nearest first, within the gate) with the tracks, updates
  // them, and returns the confirmed tracks that were hit in this frame. stamp_us must not decrease.
  std::vector<BalloonTrack> update(int64_t stamp_us,
                                   const std::vector<Eigen::Vector3d>& positions_m);

  // Every live track, confirmed or not.
  const std::vector<BalloonTrack>& tracks() const { return tracks_; }

 private:
  BalloonTrackerParams params_;
  std::vector<BalloonTrack> tracks_;
  int next_id_ = 1;
  int64_t last_stamp_us_ = 0;
};

}  // namespace uavsim::vision
