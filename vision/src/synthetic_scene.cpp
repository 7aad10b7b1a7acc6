#include "uavsim/vision/synthetic_scene.hpp"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "uavsim/common/angles.hpp"

namespace uavsim::vision::synthetic {

using common::kPi;

namespace {

// smooth random texture in [-1, 1]: coarse noise scaled up
cv::Mat smooth_noise(cv::Size size, int cell_px, uint64_t seed) {
  cv::RNG rng(seed);
  cv::Mat coarse(std::max(2, size.height / cell_px), std::max(2, size.width / cell_px), CV_32F);
  rng.fill(coarse, cv::RNG::UNIFORM, -1.0, 1.0);
  cv::Mat fine;
  cv::resize(coarse, fine, size, 0, 0, cv::INTER_CUBIC);
  return fine;
}

cv::Mat sand(cv::Size size, uint64_t seed) {
  // sand, RGB ~ (205, 180, 135): hue ~20 deg, saturation ~35%, far from green
  const cv::Mat coarse = smooth_noise(size, 24, seed);
  const cv::Mat fine = smooth_noise(size, 3, seed + 1);
  cv::Mat out(size, CV_8UC3);
  for (int y = 0; y < size.height; ++y) {
    for (int x = 0; x < size.width; ++x) {
      const double k = 1.0 + 0.12 * coarse.at<float>(y, x) + 0.06 * fine.at<float>(y, x);
      out.at<cv::Vec3b>(y, x) =
          cv::Vec3b(cv::saturate_cast<uint8_t>(135 * k), cv::saturate_cast<uint8_t>(180 * k),
                    cv::saturate_cast<uint8_t>(205 * k));
    }
  }
  return out;
}

}  // namespace

cv::Mat sky_sand_background(const PinholeIntrinsics& intrinsics, double horizon_row_px,
                            uint64_t seed) {
  const cv::Size size(intrinsics.width_px, intrinsics.height_px);
  cv::Mat out = sand(size, seed);
  const int horizon = std::clamp(static_cast<int>(horizon_row_px), 0, size.height);
  for (int y = 0; y < horizon; ++y) {
    // sky blue, paler towards the horizon: RGB (120, 175, 235) -> (185, 210, 235), hue ~105
    const double t = horizon > 1 ? static_cast<double>(y) / (horizon - 1) : 1.0;
    const cv::Vec3b c(235, cv::saturate_cast<uint8_t>(175 + 35 * t),
                      cv::saturate_cast<uint8_t>(120 + 65 * t));
    out.row(y).setTo(cv::Scalar(c[0], c[1], c[2]));
  }
  return out;
}

cv::Mat sand_background(const PinholeIntrinsics& intrinsics, uint64_t seed) {
  return sand({intrinsics.width_px, intrinsics.height_px}, seed);
}

void render_sphere(const PinholeIntrinsics& k, const Eigen::Vector3d& centre_cam_m,
                   double diameter_m, const cv::Scalar& albedo_bgr,
                   const Eigen::Vector3d& light_dir_cam, cv::Mat* image_bgr) {
  const double r_m = 0.5 * diameter_m;
  const Eigen::Vector3d& c = centre_cam_m;
  if (c.z() <= r_m) return;
  // generous bounding box: off-axis the image is an ellipse stretched radially
  const Eigen::Vector2d centre_px = k.project(c);
  const double half_px = 1.6 * k.fx_px * r_m / (c.z() - r_m) + 3.0;
  const int x0 = std::max(0, static_cast<int>(centre_px.x() - half_px));
  const int x1 = std::min(k.width_px - 1, static_cast<int>(centre_px.x() + half_px));
  const int y0 = std::max(0, static_cast<int>(centre_px.y() - half_px));
  const int y1 = std::min(k.height_px - 1, static_cast<int>(centre_px.y() + half_px));
  const Eigen::Vector3d light = light_dir_cam.normalized();
  const double c2 = c.squaredNorm() - r_m * r_m;
  constexpr int kSub = 4;  // 4x4 supersampling
  for (int y = y0; y <= y1; ++y) {
    for (int x = x0; x <= x1; ++x) {
      double coverage = 0.0;
      Eigen::Vector3d colour = Eigen::Vector3d::Zero();
      for (int sy = 0; sy < kSub; ++sy) {
        for (int sx = 0; sx < kSub; ++sx) {
          // sample positions inside the pixel (pixel centres are integers)
          const double u = x - 0.5 + (sx + 0.5) / kSub;
          const double v = y - 0.5 + (sy + 0.5) / kSub;
          const Eigen::Vector3d d = k.ray_cam({u, v});
          // ray-sphere: t^2 - 2 t (d.c) + |c|^2 - R^2 = 0, nearest root
          const double b = d.dot(c);
          const double disc = b * b - c2;
          if (disc < 0.0) continue;
          const Eigen::Vector3d p = (b - std::sqrt(disc)) * d;
          const Eigen::Vector3d n = (p - c) / r_m;
          // Lambert with ambient (sun from above, sky fill), plus a small Blinn highlight
          const double diffuse = 0.3 + 0.7 * std::max(0.0, n.dot(light));
          const Eigen::Vector3d h = (light - d).normalized();
          const double spec = 0.25 * std::pow(std::max(0.0, n.dot(h)), 40.0);
          for (int ch = 0; ch < 3; ++ch) colour(ch) += albedo_bgr[ch] * diffuse + 255.0 * spec;
          coverage += 1.0;
        }
      }
      if (coverage == 0.0) continue;
      colour /= coverage;
      const double alpha = coverage / (kSub * kSub);
      cv::Vec3b& px = image_bgr->at<cv::Vec3b>(y, x);
      for (int ch = 0; ch < 3; ++ch) {
        px[ch] = cv::saturate_cast<uint8_t>((1.0 - alpha) * px[ch] + alpha * colour(ch));
      }
    }
  }
}

void render_green_clutter(uint64_t seed, cv::Mat* image_bgr) {
  cv::RNG rng(seed);
  const int w = image_bgr->cols;
  const int h = image_bgr->rows;
  // a bush: a star-shaped green blob (spiky, so not round)
  {
    const cv::Point2d c(rng.uniform(0.15, 0.45) * w, rng.uniform(0.5, 0.85) * h);
    const double r = rng.uniform(0.06, 0.12) * h;
    std::vector<cv::Point> poly;
    constexpr int kSpikes = 9;
    for (int i = 0; i < 2 * kSpikes; ++i) {
      const double a = kPi * i / kSpikes;
      const double rr = (i % 2 == 0 ? 1.0 : 0.45) * r * rng.uniform(0.85, 1.15);
      poly.emplace_back(cvRound(c.x + rr * std::cos(a)), cvRound(c.y + rr * std::sin(a)));
    }
    cv::fillPoly(*image_bgr, std::vector<std::vector<cv::Point>>{poly}, {40, 150, 55}, cv::LINE_AA);
  }
  // a green board
  {
    const int bw = static_cast<int>(rng.uniform(0.12, 0.2) * w);
    const int bh = static_cast<int>(rng.uniform(0.05, 0.09) * h);
    const cv::Point p(static_cast<int>(rng.uniform(0.55, 0.75) * w),
                      static_cast<int>(rng.uniform(0.2, 0.6) * h));
    cv::rectangle(*image_bgr, cv::Rect(p.x, p.y, bw, bh), {50, 170, 70}, cv::FILLED, cv::LINE_AA);
  }
  // a thin green pole
  {
    const int x = static_cast<int>(rng.uniform(0.45, 0.55) * w);
    cv::rectangle(*image_bgr, cv::Rect(x, h / 3, std::max(3, w / 80), h / 2), {30, 120, 40},
                  cv::FILLED);
  }
}

void render_marker(const PinholeIntrinsics& k, const CameraPose& pose,
                   const LandingMarkerGeometry& g, const Eigen::Vector2d& marker_centre_enu_m,
                   double marker_yaw_rad, double deck_height_enu_m, cv::Mat* image_bgr) {
  // the marker as a texture, 5 mm per texel: dark square, white ring, white cross
  constexpr double kTexelM = 0.005;
  const int n = static_cast<int>(std::lround(g.square_side_m / kTexelM));
  const double mid = 0.5 * (n - 1);
  cv::Mat tex(n, n, CV_8UC3, cv::Scalar(45, 45, 45));
  constexpr int kShift = 4;  // sub-texel drawing precision
  const cv::Point centre(cvRound(mid * (1 << kShift)), cvRound(mid * (1 << kShift)));
  auto texels = [&](double m) { return cvRound(m / kTexelM * (1 << kShift)); };
  cv::circle(tex, centre, texels(g.ring_outer_radius_m), {235, 235, 235}, cv::FILLED, cv::LINE_AA,
             kShift);
  cv::circle(tex, centre, texels(g.ring_inner_radius_m), {45, 45, 45}, cv::FILLED, cv::LINE_AA,
             kShift);
  const double l = g.cross_half_length_m / kTexelM;
  const double hw = g.cross_half_width_m / kTexelM;
  cv::rectangle(tex, cv::Rect2d(mid - l, mid - hw, 2 * l, 2 * hw), {235, 235, 235}, cv::FILLED);
  cv::rectangle(tex, cv::Rect2d(mid - hw, mid - l, 2 * hw, 2 * l), {235, 235, 235}, cv::FILLED);
  // pre-filter against aliasing: the image samples the texture several texels apart
  cv::GaussianBlur(tex, tex, {0, 0}, 1.5);

  // texel (u, v, 1) -> world: x east along u, y north against v, rotated by the marker's yaw
  const double cy = std::cos(marker_yaw_rad), sy = std::sin(marker_yaw_rad);
  Eigen::Matrix3d a;  // columns: d world / du, d world / dv, world at texel (0, 0)
  const Eigen::Vector3d du(kTexelM * cy, kTexelM * sy, 0.0);
  const Eigen::Vector3d dv(kTexelM * sy, -kTexelM * cy, 0.0);
  const Eigen::Vector3d origin =
      Eigen::Vector3d(marker_centre_enu_m.x(), marker_centre_enu_m.y(), deck_height_enu_m) -
      mid * du - mid * dv;
  a.col(0) = du;
  a.col(1) = dv;
  a.col(2) = origin - pose.position_enu_m;
  // plane homography: image ~ K R_cam_enu (world - camera position)
  Eigen::Matrix3d kk;
  kk << k.fx_px, 0, k.cx_px, 0, k.fy_px, k.cy_px, 0, 0, 1;
  const Eigen::Matrix3d h = kk * pose.R_enu_cam.transpose() * a;
  cv::Matx33d hcv;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) hcv(r, c) = h(r, c);

  cv::Mat warped, alpha;
  const cv::Size size(k.width_px, k.height_px);
  cv::warpPerspective(tex, warped, hcv, size, cv::INTER_LINEAR, cv::BORDER_CONSTANT);
  cv::warpPerspective(cv::Mat(n, n, CV_32F, cv::Scalar(1.0f)), alpha, hcv, size, cv::INTER_LINEAR,
                      cv::BORDER_CONSTANT, cv::Scalar(0.0));
  for (int y = 0; y < size.height; ++y) {
    for (int x = 0; x < size.width; ++x) {
      const float w = alpha.at<float>(y, x);
      if (w <= 0.0f) continue;
      cv::Vec3b& px = image_bgr->at<cv::Vec3b>(y, x);
      const cv::Vec3b& m = warped.at<cv::Vec3b>(y, x);
      for (int ch = 0; ch < 3; ++ch)
        px[ch] = cv::saturate_cast<uint8_t>((1 - w) * px[ch] + w * m[ch]);
    }
  }
}

void add_noise(double sigma, uint64_t seed, cv::Mat* image) {
  cv::RNG rng(seed);
  cv::Mat noise(image->size(), CV_MAKETYPE(CV_16S, image->channels()));
  rng.fill(noise, cv::RNG::NORMAL, 0.0, sigma);
  cv::Mat wide;
  image->convertTo(wide, CV_16S);
  wide += noise;
  wide.convertTo(*image, image->type());
}

}  // namespace uavsim::vision::synthetic
