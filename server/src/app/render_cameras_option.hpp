// --render-cameras CAM[:FORMAT][@FPS][,...]: cameras the server renders with no client, their
// frames thrown away, so that `--hover` with it is the floor of a mission that subscribes to those
// cameras (docs/results/performance.md). Pure: the names are checked against the world's cameras
// later (app/camera_floor.hpp), when the world is loaded.
#pragma once

#include <optional>
#include <string>
#include <vector>

namespace uavsim::server::app {

// One camera of --render-cameras.
struct RenderCamera {
  std::string camera;
  std::string format = "rgb";  // rgb, grey, depth or segmentation, as camera_subscribe names them
  std::optional<double>
      fps_hz;  // unset: the camera's own rate (what a subscription without fps gets)
};

// The frame rates --render-cameras accepts (frames per sim second); the camera's own rate must be a
// whole multiple of it, checked when the world's cameras are known.
inline constexpr double kMinRenderFps = 0.001;
inline constexpr double kMaxRenderFps = 1000.0;

// Appends the cameras of one --render-cameras value to *cameras; false with *why (naming the option
// and the bad entry) for an empty name, an unknown format, an fps that is not a number in
// [kMinRenderFps, kMaxRenderFps], or a camera already named. Thread-safe (pure).
bool parse_render_cameras(const std::string& text, std::vector<RenderCamera>* cameras,
                          std::string* why);

}  // namespace uavsim::server::app
