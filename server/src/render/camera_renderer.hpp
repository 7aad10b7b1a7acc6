// CameraRenderer: offscreen images of MJCF cameras, with the sim time, pinhole intrinsics and world
// pose of each frame. One renderer owns one GL context and serves any number of cameras of one
// model; it lives on one thread (the renderer thread), so several renderers on several threads
// render in parallel.
#pragma once

#include <mujoco/mjdata.h>
#include <mujoco/mjmodel.h>

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "render/modalities.hpp"
#include "uavsim/common/pinhole.hpp"

namespace uavsim::server::render {

enum class PixelFormat {
  kRgb8,   // 3 bytes per pixel, R G B
  kGrey8,  // 1 byte per pixel, luma Y = 0.299 R + 0.587 G + 0.114 B (ITU-R BT.601)
};

// What MuJoCo draws; every effect costs frame rate (MuJoCo's defaults, all of these on, make a
// 640x480 OSMesa frame about 5-6 times as costly: docs/results/cameras.md), so all default
// to off.
struct RenderFlags {
  bool shadows = false;
  bool reflections = false;
  bool skybox = false;
  int msaa_samples =
      0;  // 0: no multisampling; otherwise samples per pixel (the model's offsamples is ignored)
};

// Which images one render() call makes.
struct RenderPasses {
  bool colour = true;        // RGB (the camera's format) with the camera's effects
  bool depth = false;        // CameraFrame::depth_m
  bool segmentation = false; // CameraFrame::geom_ids
};

// One camera to render, named as in the MJCF.
struct CameraConfig {
  std::string camera;  // <camera name="..."> in the model
  int width_px = 640;
  int height_px = 480;
  double fps_hz = 30.0;            // frame period = round(1e6 / fps_hz) us of sim time
  std::optional<double> fovy_deg;  // vertical field of view; unset: the MJCF camera's fovy
  PixelFormat format = PixelFormat::kRgb8;
  RenderFlags flags;
  // field conditions (applied by the frame service, not the renderer): sensor noise (standard deviation
  // in pixel values 0-255, per pixel and channel), brightness variation (standard deviation of a per-frame
  // gain around 1), and latency (a frame exposed at t is delivered when sim time reaches t + latency).
  double noise_sd = 0.0;
  double brightness_sd = 0.0;
  double latency_s = 0.0;
  Modalities modalities;
  // depth field conditions (applied by the frame service; never to segmentation, which is ground truth):
  // noise as a stereo camera has it, standard deviation depth_noise_m at 1 m growing with the square of
  // the depth (sd(z) = depth_noise_m * z^2 / 1 m); a fraction depth_dropout of the valid pixels invalid
  // (no texture, no return); beyond depth_max_m nothing is measured (unset: up to the far plane)
  double depth_noise_m = 0.0;
  double depth_dropout = 0.0;
  std::optional<double> depth_max_m;
};

// The intrinsics a frame carries: the one pinhole model (common/pinhole.hpp) that vision projects with;
// a MuJoCo camera's are PinholeIntrinsics::from_fovy_deg(width, height, fovy).
using CameraIntrinsics = common::PinholeIntrinsics;

// One rendered image and what a vision pipeline needs to use it.
struct CameraFrame {
  std::string camera_name;
  int camera_id = -1;    // MuJoCo camera id in the model
  int64_t stamp_us = 0;  // sim time of the pose shown: round(d->time * 1e6)
  PixelFormat format = PixelFormat::kRgb8;
  int width_px = 0;
  int height_px = 0;
  std::vector<uint8_t> pixels;  // row-major, top row first, tightly packed (3 or 1 bytes per pixel)
  CameraIntrinsics intrinsics;
  // camera pose at stamp_us: optical centre, and the rotation from the OpenCV camera frame
  // (x right, y down, z forward along the optical axis) into the world
  Eigen::Vector3d position_enu_m = Eigen::Vector3d::Zero();
  Eigen::Matrix3d R_enu_cam = Eigen::Matrix3d::Identity();
  // depth pass (RenderPasses::depth): metres along the optical axis (the camera frame's z), same layout
  // as the pixels, NaN where nothing was hit; the clip planes the depth buffer was drawn with
  std::vector<float> depth_m;
  double depth_near_m = 0.0;
  double depth_far_m = 0.0;
  // segmentation pass (RenderPasses::segmentation): the MuJoCo geom id seen at each pixel, -1 for none
  std::vector<int32_t> geom_ids;
};

// The smallest <visual><global offwidth offheight> that lets a set of cameras render.
struct OffscreenSize {
  int width_px = 0;
  int height_px = 0;
};
OffscreenSize required_offscreen_size(const std::vector<CameraConfig>& cameras);

struct RendererOptions {
  std::string backend = "osmesa";  // "osmesa", "egl" or "auto": see make_gl_context
  // leave out of a frame the geoms wholly outside its camera's view (render/view_culling.hpp): the
  // same pixels, less vertex work; off only to compare against MuJoCo drawing everything
  bool cull_outside_view = true;
};

class CameraRenderer {
 public:
  // Creates a GL context on the calling thread, which becomes this renderer's thread, and uploads
  // the model's meshes and textures. Renderers on several threads must be constructed one at a
  // time: MuJoCo loads its GL entry points at the first one, unguarded. The model must outlive the renderer. Throws
  // std::invalid_argument for a camera the model does not have, a camera whose size exceeds the
  // model's offscreen buffer (the message names the camera and the offwidth/offheight needed), or a
  // non-positive size, fps or fovy; std::runtime_error if the GL context cannot be created.
  CameraRenderer(const mjModel* m, std::vector<CameraConfig> cameras,
                 const RendererOptions& options = {});
  ~CameraRenderer();  // renderer thread only
  CameraRenderer(const CameraRenderer&) = delete;
  CameraRenderer& operator=(const CameraRenderer&) = delete;

  // Number of cameras served; indices below are in [0, camera_count()). Thread-safe.
  int camera_count() const;
  // The configuration of camera `index`, as given to the constructor. Thread-safe.
  const CameraConfig& config(int index) const;
  // MuJoCo's id of camera `index`. Thread-safe.
  int camera_id(int index) const;
  // Index of the camera with this MJCF name, or nullopt if this renderer does not serve it.
  // Thread-safe.
  std::optional<int> find(std::string_view camera_name) const;
  // Intrinsics of camera `index` (with its fovy override applied). Thread-safe.
  CameraIntrinsics intrinsics(int index) const;

  // The GL backend that renders ("osmesa", "egl"). Thread-safe.
  std::string_view gl_backend() const;
  // For the startup log: the backend, what renders (platform, GL renderer and version) and, where
  // "auto" fell back to OSMesa, why EGL did not work. Thread-safe.
  const std::string& gl_summary() const;

  // Whether camera `index` is due for a frame at d->time: frames fall on the grid k * period_us,
  // and a camera is due once sim time reaches the first grid point after its last frame (the first
  // frame is due at once). Renderer thread only.
  bool due(const mjData* d, int index) const;

  // Renders camera `index` as `d` shows the world now, into `out` (its pixel buffer is reused).
  // `d` must be forwarded: its positions (xpos, geom_xpos, cam_xpos, ...) must be those of d->qpos
  // at d->time, as after mj_forward or mj_step1. After a plain mj_step they lag one step behind
  // d->time. The renderer writes nothing in `d` (mjv_updateScene merely takes it non-const).
  // Renderer thread only; nothing may write `d` meanwhile: give a renderer thread its own copy
  // (mj_copyData) of a forwarded mjData.
  void render(mjData* d, int index, CameraFrame* out);
  // The same, with the passes asked for: colour (pixels), and depth and segmentation from one more pass
  // of flat, unlit geometry (no effects, no multisampling: edges stay exact ids). The extra pass's results
  // come from the same scene, so every image of one call shows the same instant from the same pose. A
  // pass not asked for leaves its vector empty. Renderer thread only.
  void render(mjData* d, int index, const RenderPasses& passes, CameraFrame* out);

 private:
  // the depth and segmentation pass of the scene render() has just built
  void render_geometry(int width_px, int height_px, const RenderPasses& passes, CameraFrame* out);
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace uavsim::server::render
