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

// A line of text; vehicle >= 0 draws it in that vehicle's colour (vehicle_colour_rgb).
struct OverlayLine {
  std::string text;
  int vehicle = -1;
};

// A place where something happened (a balloon popped, a landing on the target, a crash), drawn
// where it is in the image from then on: a cross in the vehicle's colour and a short text.
struct OverlayMarker {
  Eigen::Vector3d position_enu_m = Eigen::Vector3d::Zero();
  int vehicle = -1;
  std::string text;
};

// What the overlay says at one frame, taken on the loop thread at the frame's sim time.
struct OverlayInfo {
  double time_s = 0.0;
  std::vector<OverlayVehicle> vehicles;  // vehicle order, as the frame's tracked positions
  std::vector<OverlayLine> events;       // recent event lines, oldest first
  std::vector<std::string> counters;     // "balloons popped 2/5", "landed on target 1"
  std::vector<OverlayMarker> markers;
  // per vehicle (vehicle order): where it was over the last seconds, oldest first
  std::vector<std::vector<Eigen::Vector3d>> trails_enu_m;
};

// The colour of vehicle i in the overlay (RGB): eight that stand apart on sky and ground, then
// again. Thread-safe.
void vehicle_colour_rgb(int vehicle, uint8_t rgb[3]);

// The ring drawn around every vehicle, in pixels: it marks a vehicle however small it is in the
// image (a quad 50 m away spans a handful of pixels).
inline constexpr int kVehicleRingPx = 12;

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

// Draws info on an RGB8 image (top row first) of the camera's size, in place: the vehicles' trails,
// rings and labels (name and mode) at their projected positions (vehicles_enu_m, vehicle order) in
// their colours, the markers, the time and counters top left, the events bottom left. Thread-safe
// (pure; pixels are the caller's).
void draw_overlay(const OverlayInfo& info, const FrameCamera& camera,
                  const Eigen::Vector3d& position_enu_m, const Eigen::Matrix3d& R_enu_cam,
                  const std::vector<Eigen::Vector3d>& vehicles_enu_m, uint8_t* rgb);

// Marks an onboard camera's tile of a tiled recording (RGB8, width_px x height_px, in place): a
// border in the vehicle's colour and the label (the vehicle's and the camera's names) top left.
// Thread-safe (pure).
void draw_tile_label(const std::string& label, int vehicle, int width_px, int height_px,
                     uint8_t* rgb);

}  // namespace uavsim::server::render
