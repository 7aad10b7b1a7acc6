// Which cameras a world has and how each is rendered (docs/protocol.md "Camera frames"): every named MJCF
// camera, configured by the world's custom text
//   <text name="uavsim:camera:CAMNAME" data="width=640 height=480 fps=15 shadows=0 reflections=0 skybox=0 msaa=0"/>
// (every key optional; default 640 x 480 at 15 fps, effects off for speed: docs/results/cameras.md;
// field conditions: noise=SD brightness=SD latency_ms=MS, all 0 by default),
// what it gives: modalities=rgb+grey+depth+segmentation (default rgb+grey; depth field conditions
// depth_noise=M depth_dropout=P depth_max_m=M, all off by default),
// then by command-line overrides "CAMNAME:width=W,height=H,fps=F" ("*" for every camera).
// A camera belongs to a vehicle when its body is one of that vehicle's bodies or a gimbal body bound to it.
#pragma once

#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "render/camera_renderer.hpp"
#include "render/segmentation.hpp"

namespace uavsim::server::render {

struct CameraSetup {
  CameraConfig config;       // format is always kRgb8 here: the frame service encodes per subscriber
  int vehicle = -1;          // owning vehicle index, -1 for a world camera
  std::string vehicle_name;  // "" for a world camera
};

// Parses a modality list "rgb+grey+depth+segmentation" (any non-empty subset, '+' between names); throws
// std::invalid_argument naming `where` for an unknown or repeated name.
Modalities modalities_of(const std::string& text, const std::string& where);

// Parses "key=value key=value" (spaces or commas between pairs) into config; throws std::invalid_argument
// naming `where` and the key for an unknown key or a bad value.
void apply_camera_options(const std::string& text, const std::string& where, CameraConfig* config);

// Every named camera of the model, in camera id order, configured from the world and the overrides.
// Throws std::invalid_argument naming the camera for a bad custom text or override, an override naming
// no camera, or an fps outside (0, control_hz].
std::vector<CameraSetup> discover_cameras(const mjModel* m, const CameraOwners& owners,
                                          const std::vector<std::string>& overrides, double control_hz);

}  // namespace uavsim::server::render
