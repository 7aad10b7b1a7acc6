#include "render/overlay.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "render/frame_service.hpp"

namespace uavsim::server::render {

namespace {
constexpr int kFont = cv::FONT_HERSHEY_SIMPLEX;
constexpr int kLineHeightPx = 18;
constexpr double kScale = 0.5;
const cv::Scalar kWhite(255, 255, 255);
const cv::Scalar kBlack(0, 0, 0);

// RGB; the first two are the MBZIRC pair's (yellow, cyan)
constexpr uint8_t kPalette[8][3] = {{255, 230, 0},   {0, 220, 255},  {255, 90, 255},
                                    {255, 140, 0},   {120, 255, 80}, {255, 120, 140},
                                    {150, 160, 255}, {255, 255, 255}};

// text with a dark outline, readable on sky and ground alike
void text(cv::Mat& img, const std::string& s, cv::Point at, const cv::Scalar& colour) {
  cv::putText(img, s, at, kFont, kScale, kBlack, 3, cv::LINE_AA);
  cv::putText(img, s, at, kFont, kScale, colour, 1, cv::LINE_AA);
}

cv::Scalar colour_of(int vehicle) {
  if (vehicle < 0) return kWhite;
  uint8_t c[3];
  vehicle_colour_rgb(vehicle, c);
  return cv::Scalar(c[0], c[1], c[2]);
}

// the pixel of a point if it is in front of the camera and not absurdly far outside the image
// (OpenCV's drawing clips; coordinates beyond int range would not)
std::optional<cv::Point> pixel(const FrameCamera& camera, const Eigen::Vector3d& position_enu_m,
                               const Eigen::Matrix3d& R_enu_cam, const Eigen::Vector3d& p) {
  const auto px = project_to_pixel(camera, position_enu_m, R_enu_cam, p);
  if (!px || std::abs(px->x()) > 1e5 || std::abs(px->y()) > 1e5) return std::nullopt;
  return cv::Point(static_cast<int>(std::lround(px->x())), static_cast<int>(std::lround(px->y())));
}
}  // namespace

void vehicle_colour_rgb(int vehicle, uint8_t rgb[3]) {
  const auto& c = kPalette[static_cast<size_t>(std::max(0, vehicle)) % 8];
  rgb[0] = c[0];
  rgb[1] = c[1];
  rgb[2] = c[2];
}

std::optional<Eigen::Vector2d> project_to_pixel(const FrameCamera& camera,
                                                const Eigen::Vector3d& position_enu_m,
                                                const Eigen::Matrix3d& R_enu_cam,
                                                const Eigen::Vector3d& point_enu_m) {
  // p_cam = R_cam_enu (p - c); pinhole u = fx x / z + cx
  const Eigen::Vector3d p_cam = R_enu_cam.transpose() * (point_enu_m - position_enu_m);
  if (p_cam.z() <= 1e-6) return std::nullopt;
  return Eigen::Vector2d(camera.fx_px * p_cam.x() / p_cam.z() + camera.cx_px,
                         camera.fy_px * p_cam.y() / p_cam.z() + camera.cy_px);
}

PixelRect overlay_time_rect() { return {4, 2, 140, kLineHeightPx + 2}; }

void draw_overlay(const OverlayInfo& info, const FrameCamera& camera,
                  const Eigen::Vector3d& position_enu_m, const Eigen::Matrix3d& R_enu_cam,
                  const std::vector<Eigen::Vector3d>& vehicles_enu_m, uint8_t* rgb) {
  cv::Mat img(camera.height_px, camera.width_px, CV_8UC3, rgb);

  // trails: where each vehicle was over the last seconds
  for (size_t i = 0; i < info.trails_enu_m.size(); ++i) {
    std::vector<cv::Point> line;
    for (const Eigen::Vector3d& p : info.trails_enu_m[i]) {
      if (auto at = pixel(camera, position_enu_m, R_enu_cam, p)) line.push_back(*at);
    }
    if (line.size() >= 2) {
      cv::polylines(img, line, false, colour_of(static_cast<int>(i)), 1, cv::LINE_AA);
    }
  }

  // markers: a cross where it happened and what
  for (const OverlayMarker& m : info.markers) {
    const auto at = pixel(camera, position_enu_m, R_enu_cam, m.position_enu_m);
    if (!at) continue;
    constexpr int kArmPx = 6;
    for (int pass = 0; pass < 2; ++pass) {
      const cv::Scalar c = pass == 0 ? kBlack : colour_of(m.vehicle);
      const int thick = pass == 0 ? 4 : 2;
      cv::line(img, *at + cv::Point(-kArmPx, -kArmPx), *at + cv::Point(kArmPx, kArmPx), c, thick);
      cv::line(img, *at + cv::Point(-kArmPx, kArmPx), *at + cv::Point(kArmPx, -kArmPx), c, thick);
    }
    text(img, m.text, *at + cv::Point(kArmPx + 3, kArmPx + 12), colour_of(m.vehicle));
  }

  // vehicles: a ring in the vehicle's colour however small it is, and its name and mode beside
  for (size_t i = 0; i < info.vehicles.size() && i < vehicles_enu_m.size(); ++i) {
    const auto at = pixel(camera, position_enu_m, R_enu_cam, vehicles_enu_m[i]);
    if (!at) continue;
    if (at->x < -200 || at->y < -50 || at->x > camera.width_px + 50 ||
        at->y > camera.height_px + 50)
      continue;
    const cv::Scalar c = colour_of(static_cast<int>(i));
    cv::circle(img, *at, kVehicleRingPx, kBlack, 4, cv::LINE_AA);
    cv::circle(img, *at, kVehicleRingPx, c, 2, cv::LINE_AA);
    text(img, info.vehicles[i].name + " " + info.vehicles[i].mode,
         *at + cv::Point(kVehicleRingPx + 3, -6), c);
  }

  // top left: sim time, then the counters
  char t[48];
  std::snprintf(t, sizeof(t), "t = %.1f s", info.time_s);
  int y = kLineHeightPx - 2;
  text(img, t, cv::Point(6, y), kWhite);
  for (const std::string& c : info.counters) {
    y += kLineHeightPx;
    text(img, c, cv::Point(6, y), kWhite);
  }

  // bottom left: the recent events, newest last
  y = camera.height_px - 6 - kLineHeightPx * (static_cast<int>(info.events.size()) - 1);
  for (const OverlayLine& e : info.events) {
    text(img, e.text, cv::Point(6, y), colour_of(e.vehicle));
    y += kLineHeightPx;
  }
}

void draw_tile_label(const std::string& label, int vehicle, int width_px, int height_px,
                     uint8_t* rgb) {
  cv::Mat img(height_px, width_px, CV_8UC3, rgb);
  cv::rectangle(img, cv::Rect(0, 0, width_px, height_px), colour_of(vehicle), 2);
  text(img, label, cv::Point(6, kLineHeightPx - 2), colour_of(vehicle));
}

}  // namespace uavsim::server::render
