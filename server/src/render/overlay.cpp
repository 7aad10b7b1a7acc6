#include "render/overlay.hpp"

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
const cv::Scalar kYellow(255, 230, 0);  // RGB

// text with a dark outline, readable on sky and ground alike
void text(cv::Mat& img, const std::string& s, cv::Point at, const cv::Scalar& colour) {
  cv::putText(img, s, at, kFont, kScale, kBlack, 3, cv::LINE_AA);
  cv::putText(img, s, at, kFont, kScale, colour, 1, cv::LINE_AA);
}
}  // namespace

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

  // vehicle labels: name and mode beside a ring around the projected position
  for (size_t i = 0; i < info.vehicles.size() && i < vehicles_enu_m.size(); ++i) {
    const auto px = project_to_pixel(camera, position_enu_m, R_enu_cam, vehicles_enu_m[i]);
    if (!px) continue;
    const cv::Point at(static_cast<int>(px->x()), static_cast<int>(px->y()));
    if (at.x < -200 || at.y < -50 || at.x > camera.width_px + 50 || at.y > camera.height_px + 50)
      continue;
    cv::circle(img, at, 10, kYellow, 1, cv::LINE_AA);
    text(img, info.vehicles[i].name + " " + info.vehicles[i].mode, at + cv::Point(13, -6), kYellow);
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
  for (const std::string& e : info.events) {
    text(img, e, cv::Point(6, y), kWhite);
    y += kLineHeightPx;
  }
}

}  // namespace uavsim::server::render
