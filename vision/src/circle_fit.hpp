// Least-squares circle fit shared by the detectors (private header).
#pragma once

#include <opencv2/core.hpp>
#include <vector>

namespace uavsim::vision::detail {

struct CircleFit {
  cv::Point2d centre_px;
  double radius_px = 0.0;
  double rms_residual_px = 0.0;  // rms of (distance to centre - radius)
  bool ok = false;
};

// Algebraic (Kasa 1976) fit: minimises sum (x^2 + y^2 + D x + E y + F)^2, a linear 3x3 problem;
// unbiased enough for full outlines, which is what the detectors give it.
CircleFit fit_circle(const std::vector<cv::Point2d>& points_px);

}  // namespace uavsim::vision::detail
