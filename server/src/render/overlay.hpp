// The text burnt into recorded frames (uavsim-server --record): sim time, each vehicle's name and
// flight mode next to where it is in the image, the recent events (a few seconds each) and the
// mission counters the server knows. Drawn with OpenCV on the RGB frame before it goes to the
// encoder: only when recording, never on the physics path.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace uavsim::server::render {

struct FrameCamera;

struct OverlayVehicle {
  std::string name;
  std::string mode;  // "GUIDED", "LAND", ... ; "CRASHED" for a dead vehicle
};

// What the overlay says at one frame, taken on the loop thread at the frame's sim time.
struct OverlayInfo {
  double time_s = 0.0;
  std::vector<OverlayVehicle> vehicles;  // vehicle order, as the frame's tracked positions
  std::vector<std::string> events;       // recent event lines, oldest first
  std::vector<std::string> counters;     // "balloons popped 2/5", "landed on target 1"
};

// The pixel (OpenCV convention) where a camera at (position_enu_m, R_enu_cam) with the intrinsics
// of `camera` sees point_enu_m; nullopt behind the camera. Thread-safe (pure).
std::optional<Eigen::Vector2d> project_to_pixel(const FrameCamera& camera,
                                                const Eigen::Vector3d& position_enu_m,
                                                const Eigen::Matrix3d& R_enu_cam,
                                                const Eigen::Vector3d& point_enu_m);

// The rectangle (x, y, width, height in pixels) the sim-time line takes in the top-left corner.
struct PixelRect {
  int x_px = 0, y_px = 0, width_px = 0, height_px = 0;
};
PixelRect overlay_time_rect();

// Draws info on an RGB8 image (top row first) of the camera's size, in place: the vehicles' labels
// at their projected positions (vehicles_enu_m, vehicle order), the time and counters top left, the
// events bottom left. Thread-safe (pure; pixels are the caller's).
void draw_overlay(const OverlayInfo& info, const FrameCamera& camera,
                  const Eigen::Vector3d& position_enu_m, const Eigen::Matrix3d& R_enu_cam,
                  const std::vector<Eigen::Vector3d>& vehicles_enu_m, uint8_t* rgb);

}  // namespace uavsim::server::render
