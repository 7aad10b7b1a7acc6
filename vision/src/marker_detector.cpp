#include "uavsim/vision/marker_detector.hpp"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "uavsim/common/angles.hpp"

namespace uavsim::vision {

using common::kPi;

namespace {

// rms of (normalised elliptic radius - 1) of an outline about its fitted ellipse: 0 for a perfect
// ellipse
double ellipse_residual(const std::vector<cv::Point>& outline, const cv::RotatedRect& e) {
  const double a = 0.5 * e.size.width;
  const double b = 0.5 * e.size.height;
  const double c = std::cos(e.angle * kPi / 180.0);
  const double s = std::sin(e.angle * kPi / 180.0);
  double sum_sq = 0.0;
  for (const auto& p : outline) {
    const double dx = p.x - e.center.x;
    const double dy = p.y - e.center.y;
    const double u = (c * dx + s * dy) / a;
    const double v = (-s * dx + c * dy) / b;
    const double d = std::sqrt(u * u + v * v) - 1.0;
    sum_sq += d * d;
  }
  return std::sqrt(sum_sq / outline.size());
}

}  // namespace

MarkerDetector::MarkerDetector(const MarkerDetectorParams& params) : params_(params) {}

std::optional<MarkerDetection> MarkerDetector::detect(const cv::Mat& image) {
  candidates_.clear();
  if (image.empty()) return std::nullopt;
  if (image.type() == CV_8UC3) {
    cv::cvtColor(image, gray_, cv::COLOR_BGR2GRAY);
  } else if (image.type() == CV_8UC1) {
    gray_ = image;
  } else {
    return std::nullopt;
  }

  // white paint vs dark deck, at two levels: Otsu's split, which a bright truck body or deck in
  // view can push above the paint (shade, or a renderer's shadow acne, greys it), and a share of
  // it, which still splits paint from the dark square around it; the square's border keeps the
  // ring a component of its own at either level. Candidates found at both are kept once.
  search_levels(gray_);
  std::sort(candidates_.begin(), candidates_.end(),
            [](const auto& a, const auto& b) { return a.radius_px > b.radius_px; });
  if (candidates_.empty()) return std::nullopt;
  return candidates_.front();
}

void MarkerDetector::search_levels(const cv::Mat& gray) {
  const double otsu = cv::threshold(gray, binary_, 0, 255, cv::THRESH_BINARY | cv::THRESH_OTSU);
  find_candidates(binary_);
  if (params_.low_threshold_share > 0.0 && params_.low_threshold_share < 1.0) {
    cv::threshold(gray, binary_, otsu * params_.low_threshold_share, 255, cv::THRESH_BINARY);
    find_candidates(binary_);
  }
}

void MarkerDetector::find_candidates(const cv::Mat& binary) {
  std::vector<std::vector<cv::Point>> contours;
  std::vector<cv::Vec4i> hierarchy;
  cv::findContours(binary, contours, hierarchy, cv::RETR_CCOMP, cv::CHAIN_APPROX_NONE);

  const double min_area_px = kPi * params_.min_radius_px * params_.min_radius_px;
  for (size_t i = 0; i < contours.size(); ++i) {
    // outer boundaries of white components that have holes (the ring's inside)
    if (hierarchy[i][3] >= 0 || hierarchy[i][2] < 0) continue;
    const auto& outline = contours[i];
    if (outline.size() < 12) continue;
    const double outer_area_px = cv::contourArea(outline);
    if (outer_area_px < min_area_px) continue;

    // the ring's outline is an ellipse under perspective
    const cv::RotatedRect e = cv::fitEllipse(outline);
    const double major = std::max(e.size.width, e.size.height);
    const double minor = std::min(e.size.width, e.size.height);
    if (minor <= 0.0 || major / minor > params_.max_axis_ratio) continue;
    if (ellipse_residual(outline, e) > params_.max_ellipse_residual) continue;
    // the region inside the ring is partly dark: ring + cross over the whole disc. The cross does
    // not touch the ring, so it is an island in the ring's hole: count white pixels inside the
    // outline rather than subtract the holes' areas (which would leave the cross out)
    int largest_hole = -1;
    double largest_hole_area_px = 0.0;
    for (int h = hierarchy[i][2]; h >= 0; h = hierarchy[h][0]) {
      const double a = cv::contourArea(contours[h]);
      if (a > largest_hole_area_px) {
        largest_hole_area_px = a;
        largest_hole = h;
      }
    }
    const cv::Rect box = cv::boundingRect(outline);
    disc_.create(box.size(), CV_8UC1);
    disc_.setTo(0);
    cv::drawContours(disc_, contours, static_cast<int>(i), cv::Scalar(255), cv::FILLED, cv::LINE_8,
                     cv::noArray(), 0, -box.tl());
    const int disc_px = cv::countNonZero(disc_);
    cv::bitwise_and(disc_, binary(box), disc_);
    const double white_fraction = static_cast<double>(cv::countNonZero(disc_)) / disc_px;
    if (white_fraction < params_.min_white_fraction ||
        white_fraction > params_.max_white_fraction) {
      continue;
    }

    MarkerDetection d;
    d.white_fraction = white_fraction;
    // outline through edge-pixel centres: the true edge is half a pixel further out
    d.radius_px = 0.5 * std::sqrt(e.size.width * e.size.height) + 0.5;
    d.centre_px = e.center;
    // the inner edge of the ring is a second, independent estimate of the same centre
    if (largest_hole >= 0 && contours[largest_hole].size() >= 12) {
      const cv::RotatedRect inner = cv::fitEllipse(contours[largest_hole]);
      if (cv::norm(cv::Point2d(inner.center) - d.centre_px) < 0.1 * d.radius_px) {
        d.centre_px = 0.5 * (d.centre_px + cv::Point2d(inner.center));
      }
    }

    // Circle Hough Transform around the candidate (seed 7.1, fig. 7.4): it must see a circle of
    // about the ring's size centred on it; its centre is averaged in
    if (params_.hough_refine) {
      const int margin = static_cast<int>(std::ceil(d.radius_px * 1.3)) + 2;
      const cv::Rect roi =
          cv::Rect(static_cast<int>(d.centre_px.x) - margin,
                   static_cast<int>(d.centre_px.y) - margin, 2 * margin, 2 * margin) &
          cv::Rect(0, 0, gray_.cols, gray_.rows);
      cv::Mat blurred;
      cv::GaussianBlur(gray_(roi), blurred, {5, 5}, 1.2);
      std::vector<cv::Vec3f> circles;
      cv::HoughCircles(blurred, circles, cv::HOUGH_GRADIENT, 1.0, d.radius_px, 120.0,
                       std::max(10.0, 0.4 * d.radius_px), static_cast<int>(0.5 * minor * 0.9),
                       static_cast<int>(std::ceil(0.5 * major * 1.1)) + 1);
      for (const auto& c : circles) {
        const cv::Point2d hough_centre(c[0] + roi.x, c[1] + roi.y);
        if (cv::norm(hough_centre - d.centre_px) < 0.15 * d.radius_px) {
          d.centre_px = 0.5 * (d.centre_px + hough_centre);
          d.hough_refined = true;
          break;
        }
      }
    }
    // the same marker from the other threshold level: keep the first
    const bool known =
        std::any_of(candidates_.begin(), candidates_.end(), [&](const MarkerDetection& c) {
          return cv::norm(c.centre_px - d.centre_px) < 0.25 * c.radius_px;
        });
    if (!known) candidates_.push_back(d);
  }
}

std::optional<Eigen::Vector3d> marker_position_enu(const MarkerDetection& detection,
                                                   const PinholeIntrinsics& intrinsics,
                                                   const CameraPose& pose,
                                                   double deck_height_enu_m) {
  return pixel_to_plane_enu(intrinsics, pose, {detection.centre_px.x, detection.centre_px.y},
                            deck_height_enu_m);
}

}  // namespace uavsim::vision
