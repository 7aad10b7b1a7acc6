#include "circle_fit.hpp"

#include <Eigen/Dense>
#include <cmath>

namespace uavsim::vision::detail {

CircleFit fit_circle(const std::vector<cv::Point2d>& points_px) {
  CircleFit fit;
  if (points_px.size() < 3) return fit;
  // centre the points first so the normal equations stay well conditioned at any image position
  cv::Point2d mean(0, 0);
  for (const auto& p : points_px) mean += p;
  mean *= 1.0 / points_px.size();
  Eigen::Matrix3d a = Eigen::Matrix3d::Zero();
  Eigen::Vector3d b = Eigen::Vector3d::Zero();
  for (const auto& p : points_px) {
    const double x = p.x - mean.x;
    const double y = p.y - mean.y;
    const Eigen::Vector3d row(x, y, 1.0);
    a += row * row.transpose();
    b -= row * (x * x + y * y);
  }
  const Eigen::Vector3d def = a.ldlt().solve(b);
  const double cx = -0.5 * def(0);
  const double cy = -0.5 * def(1);
  const double r2 = cx * cx + cy * cy - def(2);
  if (!(r2 > 0.0) || !std::isfinite(r2)) return fit;
  fit.centre_px = {cx + mean.x, cy + mean.y};
  fit.radius_px = std::sqrt(r2);
  double sum_sq = 0.0;
  for (const auto& p : points_px) {
    const double d = std::hypot(p.x - fit.centre_px.x, p.y - fit.centre_px.y) - fit.radius_px;
    sum_sq += d * d;
  }
  fit.rms_residual_px = std::sqrt(sum_sq / points_px.size());
  fit.ok = true;
  return fit;
}

}  // namespace uavsim::vision::detail
