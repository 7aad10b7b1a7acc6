#include "render/camera_renderer.hpp"

#include <mujoco/mujoco.h>

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <thread>

#include "render/gl_context.hpp"
#include "render/view_culling.hpp"
#include "uavsim/common/angles.hpp"

namespace uavsim::server::render {

namespace {

using common::kPi;
constexpr int kMinSceneGeoms =
    1000;  // mjvScene capacity floor: decor geoms come on top of the model's

// fixed-point BT.601 luma weights, scaled by 2^16: 0.299, 0.587, 0.114
constexpr uint32_t kLumaR = 19595;
constexpr uint32_t kLumaG = 38470;
constexpr uint32_t kLumaB = 7471;

std::string size_text(int w, int h) { return std::to_string(w) + "x" + std::to_string(h); }

// one mjrContext per MSAA sample count used by the cameras; usually just one
struct MjrSlot {
  int samples = 0;
  mjrContext con;
};

struct CameraSlot {
  CameraConfig config;
  int id = -1;
  double fovy_deg = 0.0;    // effective: the override or the model's
  double fovy_scale = 1.0;  // tan(fovy/2) / tan(model fovy/2), applied to the scene's frustum
  int64_t period_us = 0;
  std::optional<int64_t> last_stamp_us;
  MjrSlot* mjr = nullptr;
};

}  // namespace

OffscreenSize required_offscreen_size(const std::vector<CameraConfig>& cameras) {
  OffscreenSize size;
  for (const CameraConfig& c : cameras) {
    size.width_px = std::max(size.width_px, c.width_px);
    size.height_px = std::max(size.height_px, c.height_px);
  }
  return size;
}

struct CameraRenderer::Impl {
  const mjModel* m = nullptr;
  std::unique_ptr<GlContext> gl;
  std::string gl_summary;
  std::thread::id thread;
  std::vector<CameraSlot> cameras;
  std::vector<std::unique_ptr<MjrSlot>> mjr;
  mjvScene scn;
  mjvOption opt;
  std::vector<uint8_t> rgb;  // bottom-up scratch image from mjr_readPixels
  std::vector<float> depth;  // bottom-up scratch depth buffer (0 near .. 1 far) from mjr_readPixels
  MjrSlot* geometry_mjr = nullptr;  // the depth and segmentation pass's context: no multisampling
  bool cull_outside_view = true;

  void make_current() const {
    assert(std::this_thread::get_id() == thread && "CameraRenderer used off its renderer thread");
    if (!gl->make_current()) throw std::runtime_error("render: cannot make the GL context current");
  }

  MjrSlot* mjr_for_samples(int samples) {
    for (auto& slot : mjr) {
      if (slot->samples == samples) return slot.get();
    }
    // mjr_makeContext reads the sample count from the model: give it a shallow copy that differs
    // only there (the copy shares the model's arrays and is read only for the duration of the call)
    auto slot = std::make_unique<MjrSlot>();
    slot->samples = samples;
    mjModel with_samples = *m;
    with_samples.vis.quality.offsamples = samples;
    mjr_defaultContext(&slot->con);
    mjr_makeContext(&with_samples, &slot->con, mjFONTSCALE_50);
    if (slot->con.offFBO == 0) {
      mjr_freeContext(&slot->con);
      throw std::runtime_error("render: MuJoCo could not create its offscreen framebuffer (" +
                               std::string(gl->name()) + ")");
    }
    mjr.push_back(std::move(slot));
    return mjr.back().get();
  }
};

CameraRenderer::CameraRenderer(const mjModel* m, std::vector<CameraConfig> cameras,
                               const RendererOptions& options)
    : impl_(std::make_unique<Impl>()) {
  assert(m != nullptr);
  Impl& s = *impl_;
  s.m = m;
  s.thread = std::this_thread::get_id();
  s.cull_outside_view = options.cull_outside_view;

  // resolve and check every camera before touching GL
  const int off_w = m->vis.global.offwidth;
  const int off_h = m->vis.global.offheight;
  for (CameraConfig& config : cameras) {
    const int id = mj_name2id(m, mjOBJ_CAMERA, config.camera.c_str());
    if (id < 0) {
      throw std::invalid_argument("render: the model has no camera named '" + config.camera + "'");
    }
    if (config.width_px <= 0 || config.height_px <= 0 || !(config.fps_hz > 0.0)) {
      throw std::invalid_argument("render: camera '" + config.camera +
                                  "' needs a positive size and fps, got " +
                                  size_text(config.width_px, config.height_px) + " at " +
                                  std::to_string(config.fps_hz) + " fps");
    }
    if (config.fovy_deg && !(*config.fovy_deg > 0.0 && *config.fovy_deg < 180.0)) {
      throw std::invalid_argument("render: camera '" + config.camera +
                                  "' fovy_deg must be in (0, 180), got " +
                                  std::to_string(*config.fovy_deg));
    }
    if (config.width_px > off_w || config.height_px > off_h) {
      throw std::invalid_argument(
          "render: camera '" + config.camera + "' asks for " +
          size_text(config.width_px, config.height_px) + " but the model's offscreen buffer is " +
          size_text(off_w, off_h) + ": set <visual><global offwidth=\"" +
          std::to_string(std::max(off_w, config.width_px)) + "\" offheight=\"" +
          std::to_string(std::max(off_h, config.height_px)) + "\"/> in the world MJCF");
    }
    CameraSlot slot;
    slot.id = id;
    const double model_fovy = m->cam_fovy[id];
    slot.fovy_deg = config.fovy_deg.value_or(model_fovy);
    slot.fovy_scale =
        std::tan(0.5 * slot.fovy_deg * kPi / 180.0) / std::tan(0.5 * model_fovy * kPi / 180.0);
    slot.period_us = std::max<int64_t>(1, std::llround(1e6 / config.fps_hz));
    slot.config = std::move(config);
    s.cameras.push_back(std::move(slot));
  }

  // GL context, then one MuJoCo render context per MSAA sample count in use
  std::string fallback_reason;
  s.gl = make_gl_context(options.backend, &fallback_reason);
  s.make_current();
  s.gl_summary = std::string(s.gl->name()) + " (" + s.gl->detail() + ")";
  if (!fallback_reason.empty()) s.gl_summary += "; auto: EGL unavailable: " + fallback_reason;
  for (CameraSlot& cam : s.cameras) {
    cam.mjr = s.mjr_for_samples(std::max(0, cam.config.flags.msaa_samples));
    if (cam.config.modalities.geometry()) s.geometry_mjr = s.mjr_for_samples(0);
  }

  // MuJoCo may clamp the offscreen buffer to what the GL implementation allows
  for (const CameraSlot& cam : s.cameras) {
    if (cam.config.width_px > cam.mjr->con.offWidth ||
        cam.config.height_px > cam.mjr->con.offHeight) {
      throw std::invalid_argument("render: camera '" + cam.config.camera + "' asks for " +
                                  size_text(cam.config.width_px, cam.config.height_px) +
                                  " but the GL offscreen buffer is only " +
                                  size_text(cam.mjr->con.offWidth, cam.mjr->con.offHeight));
    }
  }

  // one scene for all cameras; camera images show geoms only, no sites or sensor rays
  mjv_defaultOption(&s.opt);
  std::fill(std::begin(s.opt.sitegroup), std::end(s.opt.sitegroup), 0);
  s.opt.flags[mjVIS_RANGEFINDER] = 0;
  mjv_defaultScene(&s.scn);
  mjv_makeScene(m, &s.scn, std::max(kMinSceneGeoms, 2 * m->ngeom));
}

CameraRenderer::~CameraRenderer() {
  Impl& s = *impl_;
  mjv_freeScene(&s.scn);
  if (s.gl && s.gl->make_current()) {
    for (auto& slot : s.mjr) mjr_freeContext(&slot->con);
    s.gl->release();
  }
}

int CameraRenderer::camera_count() const { return static_cast<int>(impl_->cameras.size()); }

const CameraConfig& CameraRenderer::config(int index) const {
  return impl_->cameras.at(index).config;
}

int CameraRenderer::camera_id(int index) const { return impl_->cameras.at(index).id; }

std::optional<int> CameraRenderer::find(std::string_view camera_name) const {
  for (size_t i = 0; i < impl_->cameras.size(); ++i) {
    if (impl_->cameras[i].config.camera == camera_name) return static_cast<int>(i);
  }
  return std::nullopt;
}

std::string_view CameraRenderer::gl_backend() const { return impl_->gl->name(); }

const std::string& CameraRenderer::gl_summary() const { return impl_->gl_summary; }

CameraIntrinsics CameraRenderer::intrinsics(int index) const {
  const CameraSlot& cam = impl_->cameras.at(index);
  return CameraIntrinsics::from_fovy_deg(cam.config.width_px, cam.config.height_px, cam.fovy_deg);
}

bool CameraRenderer::due(const mjData* d, int index) const {
  const CameraSlot& cam = impl_->cameras.at(index);
  if (!cam.last_stamp_us) return true;
  // next grid point strictly after the last frame
  const int64_t next_us = (*cam.last_stamp_us / cam.period_us + 1) * cam.period_us;
  return std::llround(d->time * 1e6) >= next_us;
}

void CameraRenderer::render(mjData* d, int index, CameraFrame* out) {
  render(d, index, RenderPasses{}, out);
}

void CameraRenderer::render(mjData* d, int index, const RenderPasses& passes, CameraFrame* out) {
  assert(d != nullptr && out != nullptr);
  Impl& s = *impl_;
  CameraSlot& cam = s.cameras.at(index);
  const int w = cam.config.width_px;
  const int h = cam.config.height_px;
  const size_t pixels = static_cast<size_t>(w) * h;
  s.make_current();

  // scene from the fixed MJCF camera
  mjvCamera view;
  mjv_defaultCamera(&view);
  view.type = mjCAMERA_FIXED;
  view.fixedcamid = cam.id;
  mjv_updateScene(s.m, d, &s.opt, nullptr, &view, mjCAT_ALL, &s.scn);

  // fovy override: scale the frustum the scene took from the model's fovy
  for (mjvGLCamera& gl_cam : s.scn.camera) {
    gl_cam.frustum_top = static_cast<float>(gl_cam.frustum_top * cam.fovy_scale);
    gl_cam.frustum_bottom = static_cast<float>(gl_cam.frustum_bottom * cam.fovy_scale);
    gl_cam.frustum_center = static_cast<float>(gl_cam.frustum_center * cam.fovy_scale);
  }

  // per-camera effects
  s.scn.flags[mjRND_SHADOW] = cam.config.flags.shadows;
  s.scn.flags[mjRND_REFLECTION] = cam.config.flags.reflections;
  s.scn.flags[mjRND_SKYBOX] = cam.config.flags.skybox;
  // shadows and reflections draw the scene from elsewhere: what this view cannot see may show in
  // them
  if (s.cull_outside_view && !cam.config.flags.shadows && !cam.config.flags.reflections) {
    remove_geoms_outside_view(s.m, w, h, &s.scn);
  }

  const mjrRect viewport = {0, 0, w, h};
  out->pixels.clear();
  if (passes.colour) {
    // render into MuJoCo's offscreen framebuffer and read it back (bottom row first)
    mjr_setBuffer(mjFB_OFFSCREEN, &cam.mjr->con);
    mjr_render(viewport, &s.scn, &cam.mjr->con);
    s.rgb.resize(pixels * 3);
    mjr_readPixels(s.rgb.data(), nullptr, viewport, &cam.mjr->con);

    // flip to top row first, converting to grey if asked
    const int channels = cam.config.format == PixelFormat::kRgb8 ? 3 : 1;
    out->pixels.resize(pixels * channels);
    for (int row = 0; row < h; ++row) {
      const uint8_t* src = s.rgb.data() + static_cast<size_t>(h - 1 - row) * w * 3;
      uint8_t* dst = out->pixels.data() + static_cast<size_t>(row) * w * channels;
      if (channels == 3) {
        std::copy(src, src + static_cast<size_t>(w) * 3, dst);
      } else {
        for (int col = 0; col < w; ++col, src += 3) {
          dst[col] = static_cast<uint8_t>(
              (kLumaR * src[0] + kLumaG * src[1] + kLumaB * src[2] + 32768) >> 16);
        }
      }
    }
  }

  out->depth_m.clear();
  out->geom_ids.clear();
  out->depth_near_m = s.scn.camera[0].frustum_near;
  out->depth_far_m = s.scn.camera[0].frustum_far;
  if (passes.depth || passes.segmentation) render_geometry(w, h, passes, out);

  // metadata: time, intrinsics and pose of what was drawn
  out->camera_name = cam.config.camera;
  out->camera_id = cam.id;
  out->stamp_us = std::llround(d->time * 1e6);
  out->format = cam.config.format;
  out->width_px = w;
  out->height_px = h;
  out->intrinsics = CameraIntrinsics::from_fovy_deg(w, h, cam.fovy_deg);
  out->position_enu_m = Eigen::Map<const Eigen::Vector3d>(d->cam_xpos + 3 * cam.id);
  // cam_xmat is row-major; its columns are MuJoCo's camera axes (x right, y up, looking along -z):
  // the OpenCV camera frame flips y and z
  const Eigen::Matrix3d R_enu_mjcam =
      Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(d->cam_xmat + 9 * cam.id);
  out->R_enu_cam = R_enu_mjcam * Eigen::Vector3d(1.0, -1.0, -1.0).asDiagonal();
  cam.last_stamp_us = out->stamp_us;
}

void CameraRenderer::render_geometry(int w, int h, const RenderPasses& passes, CameraFrame* out) {
  Impl& s = *impl_;
  const size_t pixels = static_cast<size_t>(w) * h;
  if (s.geometry_mjr == nullptr) s.geometry_mjr = s.mjr_for_samples(0);
  mjrContext* con = &s.geometry_mjr->con;

  // every model geom that shows gets its id as segid (the pass colours it segid + 1, 24 bits); decor
  // and invisible geoms get none
  for (int i = 0; i < s.scn.ngeom; ++i) {
    mjvGeom& g = s.scn.geoms[i];
    g.segid = g.objtype == mjOBJ_GEOM && g.rgba[3] > 0.0f ? g.objid : -1;
  }

  // flat, unlit, no effects: MuJoCo's segmentation mode, which also writes the depth buffer
  s.scn.flags[mjRND_SHADOW] = 0;
  s.scn.flags[mjRND_REFLECTION] = 0;
  s.scn.flags[mjRND_SKYBOX] = 0;
  s.scn.flags[mjRND_SEGMENT] = 1;
  s.scn.flags[mjRND_IDCOLOR] = 1;
  const mjrRect viewport = {0, 0, w, h};
  mjr_setBuffer(mjFB_OFFSCREEN, con);
  mjr_render(viewport, &s.scn, con);
  s.rgb.resize(pixels * 3);
  s.depth.resize(pixels);
  mjr_readPixels(passes.segmentation ? s.rgb.data() : nullptr, passes.depth ? s.depth.data() : nullptr,
                 viewport, con);
  s.scn.flags[mjRND_SEGMENT] = 0;
  s.scn.flags[mjRND_IDCOLOR] = 0;

  // depth buffer (OpenGL's perspective mapping, 0 at near, 1 at far) => metres along the optical axis:
  // z = n f / (f - b (f - n)); 1 is the cleared buffer: nothing hit
  if (passes.depth) {
    const double n = out->depth_near_m;
    const double f = out->depth_far_m;
    out->depth_m.resize(pixels);
    for (int row = 0; row < h; ++row) {
      const float* src = s.depth.data() + static_cast<size_t>(h - 1 - row) * w;
      float* dst = out->depth_m.data() + static_cast<size_t>(row) * w;
      for (int col = 0; col < w; ++col) {
        const double b = src[col];
        dst[col] = b >= 1.0 ? std::numeric_limits<float>::quiet_NaN()
                            : static_cast<float>(n * f / (f - b * (f - n)));
      }
    }
  }

  // id colour => geom id (0: the cleared background)
  if (passes.segmentation) {
    out->geom_ids.resize(pixels);
    const int ngeom = s.m->ngeom;
    for (int row = 0; row < h; ++row) {
      const uint8_t* src = s.rgb.data() + static_cast<size_t>(h - 1 - row) * w * 3;
      int32_t* dst = out->geom_ids.data() + static_cast<size_t>(row) * w;
      for (int col = 0; col < w; ++col, src += 3) {
        const int32_t id = static_cast<int32_t>(src[0] | (src[1] << 8) | (src[2] << 16)) - 1;
        dst[col] = id < ngeom ? id : -1;
      }
    }
  }
}

}  // namespace uavsim::server::render
