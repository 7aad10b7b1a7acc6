#include "uavsim/vision/balloon_detector.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>

#include "circle_fit.hpp"
#include "uavsim/common/angles.hpp"

namespace uavsim::vision {

using common::kPi;

Eigen::Vector3d sphere_position_from_circle(const PinholeIntrinsics& intrinsics,
                                            const cv::Point2d& centre_px, double radius_px,
                                            double diameter_m) {
  // rays through points of the image circle form (nearly) the sphere's tangent cone; its axis is
  // their mean direction and its half-angle a gives the range: sin(a) = R / d. Valid off-axis too,
  // where the sphere's image is an ellipse and a plain f * D / (2 r) would be biased.
  constexpr int kRimSamples = 16;
  Eigen::Vector3d rays[kRimSamples];
  Eigen::Vector3d axis = Eigen::Vector3d::Zero();
  for (int i = 0; i < kRimSamples; ++i) {
    const double t = 2.0 * kPi * i / kRimSamples;
    rays[i] = intrinsics.ray_cam(
        {centre_px.x + radius_px * std::cos(t), centre_px.y + radius_px * std::sin(t)});
    axis += rays[i];
  }
  axis.normalize();
  double half_angle_rad = 0.0;
  for (const auto& ray : rays) half_angle_rad += std::acos(std::clamp(ray.dot(axis), -1.0, 1.0));
  half_angle_rad /= kRimSamples;
  const double range_m = 0.5 * diameter_m / std::sin(std::max(half_angle_rad, 1e-9));
  return axis * range_m;
}

BalloonDetector::BalloonDetector(const BalloonDetectorParams& params,
                                 const PinholeIntrinsics& intrinsics)
    : params_(params), intrinsics_(intrinsics) {}

std::vector<BalloonDetection> BalloonDetector::detect(const cv::Mat& bgr) {
  std::vector<BalloonDetection> out;
  if (bgr.empty() || bgr.type() != CV_8UC3) return out;

  // colour filter: green hue, enough saturation, not black
  cv::cvtColor(bgr, hsv_, cv::COLOR_BGR2HSV);
  cv::inRange(hsv_, cv::Scalar(params_.hue_min, params_.saturation_min, params_.value_min),
              cv::Scalar(params_.hue_max, 255, 255), mask_);
  // remove isolated noise pixels, close pinholes along the rim
  static const cv::Mat kKernel = cv::getStructuringElement(cv::MORPH_ELLIPSE, {3, 3});
  cv::morphologyEx(mask_, mask_, cv::MORPH_OPEN, kKernel);
  cv::morphologyEx(mask_, mask_, cv::MORPH_CLOSE, kKernel);

  std::vector<std::vector<cv::Point>> contours;
  cv::findContours(mask_, contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_NONE);

  const double min_area_px = kPi * params_.min_radius_px * params_.min_radius_px * 0.5;
  std::vector<cv::Point2d> rim;
  for (const auto& contour : contours) {
    const double area_px = cv::contourArea(contour);
    if (area_px < min_area_px) continue;

    // fit a circle to the outline, leaving out the image border where the blob is cut
    rim.clear();
    for (const auto& p : contour) {
      if (p.x <= 0 || p.y <= 0 || p.x >= bgr.cols - 1 || p.y >= bgr.rows - 1) continue;
      rim.emplace_back(p.x, p.y);
    }
    const detail::CircleFit fit = detail::fit_circle(rim);
    if (!fit.ok) continue;
    // shape tests: round outline, filled disc
    const double residual = fit.rms_residual_px / fit.radius_px;
    const double fill = area_px / (kPi * fit.radius_px * fit.radius_px);
    if (residual > params_.max_fit_residual || fill < params_.min_fill_ratio || fill > 1.15)
      continue;
    // the outline runs through the centres of the blob's edge pixels: the edge is half a pixel out
    const double radius_px = fit.radius_px + 0.5;
    if (radius_px < params_.min_radius_px || radius_px > params_.max_radius_px) continue;
    // reject blobs cut by the border: their centre and size are unreliable
    const double outside = std::max({0.0, radius_px - fit.centre_px.x, radius_px - fit.centre_px.y,
                                     fit.centre_px.x + radius_px - (bgr.cols - 1),
                                     fit.centre_px.y + radius_px - (bgr.rows - 1)}) /
                           (2.0 * radius_px);
    if (outside > params_.max_circle_outside) continue;

    BalloonDetection d;
    d.centre_px = fit.centre_px;
    d.radius_px = radius_px;
    d.fit_residual = residual;

    // Circle Hough Transform on the blurred mask around the candidate (seed 7.2, fig. 7.12): it
    // must find a circle of about the fitted size; its centre, robust to bumps on the outline, is
    // averaged in. The radius stays the sub-pixel least-squares one (Hough radii are whole pixels).
    constexpr double kMinHoughRadiusPx = 8.0;
    if (params_.hough_refine && radius_px >= kMinHoughRadiusPx) {
      const int margin = static_cast<int>(std::ceil(radius_px * 1.4)) + 2;
      const cv::Rect roi =
          cv::Rect(static_cast<int>(fit.centre_px.x) - margin,
                   static_cast<int>(fit.centre_px.y) - margin, 2 * margin, 2 * margin) &
          cv::Rect(0, 0, bgr.cols, bgr.rows);
      cv::GaussianBlur(mask_(roi), work_, {5, 5}, 1.2);
      std::vector<cv::Vec3f> circles;
      cv::HoughCircles(work_, circles, cv::HOUGH_GRADIENT, 1.0, radius_px, 100.0,
                       std::max(8.0, 0.5 * radius_px), static_cast<int>(radius_px * 0.8),
                       static_cast<int>(std::ceil(radius_px * 1.2)) + 1);
      for (const auto& c : circles) {
        const cv::Point2d hough_centre(c[0] + roi.x, c[1] + roi.y);
        if (cv::norm(hough_centre - fit.centre_px) < 0.25 * radius_px) {
          d.centre_px = 0.5 * (fit.centre_px + hough_centre);
          d.hough_refined = true;
          break;
        }
      }
    }

    d.position_cam_m = sphere_position_from_circle(intrinsics_, d.centre_px, d.radius_px,
                                                   params_.balloon_diameter_m);
    d.range_m = d.position_cam_m.norm();
    out.push_back(d);
  }
  std::sort(out.begin(), out.end(),
            [](const auto& a, const auto& b) { return a.radius_px > b.radius_px; });
  if (static_cast<int>(out.size()) > params_.max_detections) out.resize(params_.max_detections);
  return out;
}

BalloonTracker::BalloonTracker(const BalloonTrackerParams& params) : params_(params) {}

std::vector<BalloonTrack> BalloonTracker::update(int64_t stamp_us,
                                                 const std::vector<Eigen::Vector3d>& positions_m) {
  const double dt_s = tracks_.empty() ? 0.0 : 1e-6 * static_cast<double>(stamp_us - last_stamp_us_);
  last_stamp_us_ = stamp_us;
  // first-order low-pass: alpha = 1 - exp(-dt / tau)
  const double alpha = params_.lowpass_tau_s > 0.0
                           ? 1.0 - std::exp(-std::max(dt_s, 0.0) / params_.lowpass_tau_s)
                           : 1.0;

  // greedy nearest-neighbour association, closest pairs first
  struct Pair {
    double distance_m;
    size_t track;
    size_t detection;
  };
  std::vector<Pair> pairs;
  for (size_t t = 0; t < tracks_.size(); ++t) {
    for (size_t k = 0; k < positions_m.size(); ++k) {
      const double d = (tracks_[t].position_m - positions_m[k]).norm();
      if (d <= params_.gate_m) pairs.push_back({d, t, k});
    }
  }
  std::sort(pairs.begin(), pairs.end(),
            [](const Pair& a, const Pair& b) { return a.distance_m < b.distance_m; });
  std::vector<bool> track_hit(tracks_.size(), false);
  std::vector<bool> detection_used(positions_m.size(), false);
  for (const auto& p : pairs) {
    if (track_hit[p.track] || detection_used[p.detection]) continue;
    track_hit[p.track] = true;
    detection_used[p.detection] = true;
    BalloonTrack& track = tracks_[p.track];
    track.position_m += alpha * (positions_m[p.detection] - track.position_m);
    ++track.hits;
    track.misses = 0;
    track.last_hit_stamp_us = stamp_us;
    if (track.hits >= params_.confirm_hits) track.confirmed = true;
  }

  // misses: a miss breaks the run of consecutive hits; too many drop the track
  for (size_t t = 0; t < track_hit.size(); ++t) {
    if (track_hit[t]) continue;
    tracks_[t].hits = 0;
    ++tracks_[t].misses;
  }
  std::erase_if(tracks_, [&](const BalloonTrack& t) { return t.misses > params_.max_misses; });

  // unmatched detections start tentative tracks
  for (size_t k = 0; k < positions_m.size(); ++k) {
    if (detection_used[k]) continue;
    BalloonTrack track;
    track.id = next_id_++;
    track.position_m = positions_m[k];
    track.hits = 1;
    track.last_hit_stamp_us = stamp_us;
    track.confirmed = params_.confirm_hits <= 1;
    tracks_.push_back(track);
  }

  std::vector<BalloonTrack> confirmed;
  for (const auto& t : tracks_) {
    if (t.confirmed && t.last_hit_stamp_us == stamp_us) confirmed.push_back(t);
  }
  return confirmed;
}

}  // namespace uavsim::vision
