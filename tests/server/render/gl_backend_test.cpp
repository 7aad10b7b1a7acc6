// The two GL backends, EGL and OSMesa, render the same scene: the same pixels up to rasterisation
// noise, the same objects in the same places. EGL is a declared dependency
// (scripts/install_deps.sh), so a machine where it cannot create a context fails here rather than
// skipping.
#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include <cmath>
#include <cstdlib>
#include <memory>
#include <stdexcept>
#include <string>

#include "../../support/mjcf_scene.hpp"
#include "pixel_blob.hpp"
#include "render/camera_renderer.hpp"
#include "render/gl_context.hpp"

namespace uavsim::server::render {
namespace {

// Both backends are Mesa's llvmpipe here, so the frames should agree almost bit for bit; a GPU
// through EGL rasterises edges and lighting a little differently, which these bounds still allow.
constexpr double kMeanAbsDiffTol = 1.0;       // grey levels, mean over all pixels and channels
constexpr double kDifferentPixelsTol = 0.01;  // fraction of pixels off by more than kLargeDiff
constexpr int kLargeDiff = 24;                // grey levels in any channel
constexpr double kCentroidTol = 0.25;         // px between the backends' blob centroids
constexpr double kAreaRelTol = 0.02;          // of a blob's area, between the backends
constexpr double kProjectionTol = 2.0;        // px between a blob centroid and its projected centre

// A quad-sized vehicle (dark hull, grey arms, four rotor discs) hovering in front of a green
// balloon on a pole, over a checkered ground, lit by a sun and MuJoCo's headlight, seen by one
// camera from behind and above: shading, texture and depth all in the frame.
constexpr char kSceneXml[] = R"(
<mujoco>
  <visual>
    <global offwidth="320" offheight="240"/>
    <quality shadowsize="1024"/>
  </visual>
  <asset>
    <texture name="sky" type="skybox" builtin="gradient" rgb1="0.4 0.6 0.8" rgb2="0 0 0" width="64" height="64"/>
    <texture name="grid" type="2d" builtin="checker" rgb1="0.45 0.5 0.45" rgb2="0.35 0.4 0.35" width="256" height="256"/>
    <material name="ground" texture="grid" texrepeat="10 10" reflectance="0.2"/>
  </asset>
  <worldbody>
    <light directional="true" pos="0 0 20" dir="0.3 0.2 -1" castshadow="true"/>
    <geom type="plane" size="30 30 0.1" material="ground"/>
    <camera name="chase" pos="-4 0 3" xyaxes="0 -1 0 0.4 0 1" fovy="60"/>
    <body name="quad" pos="0 0 2">
      <freejoint/>
      <geom name="hull" type="box" size="0.15 0.15 0.05" rgba="0.05 0.05 0.3 1"/>
      <geom type="capsule" fromto="-0.2 -0.2 0 0.2 0.2 0" size="0.015" rgba="0.5 0.5 0.5 1"/>
      <geom type="capsule" fromto="-0.2 0.2 0 0.2 -0.2 0" size="0.015" rgba="0.5 0.5 0.5 1"/>
      <geom type="cylinder" pos="0.2 0.2 0.04" size="0.12 0.005" rgba="0.8 0.8 0.8 0.6"/>
      <geom type="cylinder" pos="-0.2 0.2 0.04" size="0.12 0.005" rgba="0.8 0.8 0.8 0.6"/>
      <geom type="cylinder" pos="0.2 -0.2 0.04" size="0.12 0.005" rgba="0.8 0.8 0.8 0.6"/>
      <geom type="cylinder" pos="-0.2 -0.2 0.04" size="0.12 0.005" rgba="0.8 0.8 0.8 0.6"/>
    </body>
    <body name="balloon" mocap="true" pos="3 1 0">
      <geom type="cylinder" fromto="0 0 0 0 0 2.42" size="0.02" rgba="0.6 0.6 0.6 1"/>
      <geom name="ball" type="sphere" pos="0 0 2.7" size="0.3" rgba="0 0.9 0 1"/>
    </body>
  </worldbody>
</mujoco>
)";
const Eigen::Vector3d kHullCentreEnuM(0.0, 0.0, 2.0);
const Eigen::Vector3d kBalloonCentreEnuM(3.0, 1.0, 2.7);

struct Scene : uavsim::testing::MjcfScene {
  Scene() : MjcfScene(kSceneXml, ::testing::TempDir() + "gl_backend_scene.xml") {}
};

using testing::Blob;
using testing::project;

Blob find_balloon(const CameraFrame& f) {
  return testing::find_blob(f,
                            [](int r, int g, int b) { return g > 40 && g > 2 * r && g > 2 * b; });
}
Blob find_hull(const CameraFrame& f) {
  return testing::find_blob(f,
                            [](int r, int g, int b) { return b > 40 && b > 3 * r && b > 3 * g; });
}

std::unique_ptr<GlContext> make_egl_or_explain() {
  try {
    return make_gl_context("egl");
  } catch (const std::runtime_error& e) {
    ADD_FAILURE() << "EGL cannot create a context on this machine, though it is a declared "
                     "dependency (scripts/install_deps.sh installs libegl-mesa0 and "
                     "libgl1-mesa-dri): "
                  << e.what();
    return nullptr;
  }
}

CameraFrame render_with(const Scene& s, const std::string& backend, const RenderFlags& flags) {
  CameraConfig config;
  config.camera = "chase";
  config.width_px = 320;
  config.height_px = 240;
  config.flags = flags;
  RendererOptions options;
  options.backend = backend;
  CameraRenderer renderer(s.m, {config}, options);
  CameraFrame frame;
  renderer.render(s.d, 0, &frame);
  return frame;
}

void expect_same_scene(const CameraFrame& osmesa, const CameraFrame& egl) {
  ASSERT_EQ(osmesa.pixels.size(), egl.pixels.size());
  const testing::FrameDifference diff = testing::frame_difference(osmesa, egl, kLargeDiff);
  ::testing::Test::RecordProperty("mean_abs_diff", std::to_string(diff.mean_abs_diff));
  ::testing::Test::RecordProperty("pixels_off", std::to_string(diff.large_pixels));
  EXPECT_LE(diff.mean_abs_diff, kMeanAbsDiffTol);
  EXPECT_LE(diff.large_fraction, kDifferentPixelsTol);

  // the objects where the camera model puts them, in both frames
  for (const auto& [name, find, centre] : {std::tuple{"balloon", &find_balloon, kBalloonCentreEnuM},
                                           std::tuple{"hull", &find_hull, kHullCentreEnuM}}) {
    SCOPED_TRACE(name);
    const Blob a = find(osmesa);
    const Blob b = find(egl);
    ASSERT_GT(a.area_px, 20.0) << "the scene shows no " << name;
    EXPECT_NEAR(a.u, b.u, kCentroidTol);
    EXPECT_NEAR(a.v, b.v, kCentroidTol);
    EXPECT_NEAR(a.area_px, b.area_px, kAreaRelTol * a.area_px);
    const Eigen::Vector2d at = project(osmesa, centre);
    // the balloon is a sphere: its silhouette's centroid is its centre's projection (to within the
    // perspective shift, well under a pixel here); the hull is seen from above, its top face
    // centroid lies a little off the body centre, so the bound is wider
    const double tol = std::string(name) == "balloon" ? kProjectionTol : 3 * kProjectionTol;
    EXPECT_NEAR(a.u, at.x(), tol);
    EXPECT_NEAR(a.v, at.y(), tol);
  }
}

TEST(GlBackends, EglCreatesADesktopGlContext) {
  std::unique_ptr<GlContext> gl = make_egl_or_explain();
  ASSERT_NE(gl, nullptr);
  EXPECT_EQ(gl->name(), "egl");
  ASSERT_TRUE(gl->make_current());
  EXPECT_TRUE(gl->make_current());  // already current: still fine
  // a compatibility context: the legacy GL that mjr_* uses
  EXPECT_NE(gl->detail().find("OpenGL"), std::string::npos) << gl->detail();
  EXPECT_EQ(gl->detail().find("Core Profile"), std::string::npos) << gl->detail();
  gl->release();
}

TEST(GlBackends, AutoChoosesEglWhereItCreatesAContext) {
  std::string reason = "unset";
  std::unique_ptr<GlContext> gl = make_gl_context("auto", &reason);
  EXPECT_EQ(gl->name(), "egl") << "auto fell back to OSMesa: " << reason;
  EXPECT_EQ(reason, "unset");  // untouched when EGL worked
}

TEST(GlBackends, UnknownBackendNamesTheKnownOnes) {
  try {
    make_gl_context("vulkan");
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("egl, osmesa or auto"), std::string::npos) << e.what();
  }
}

TEST(GlBackends, EglAndOsmesaRenderTheSameFrame) {
  ASSERT_NE(make_egl_or_explain(), nullptr);
  Scene s;
  const CameraFrame osmesa = render_with(s, "osmesa", {});
  const CameraFrame egl = render_with(s, "egl", {});
  expect_same_scene(osmesa, egl);
}

TEST(GlBackends, EglAndOsmesaRenderTheSameFrameWithEveryEffect) {
  ASSERT_NE(make_egl_or_explain(), nullptr);
  Scene s;
  RenderFlags all;
  all.shadows = true;
  all.reflections = true;
  all.skybox = true;
  all.msaa_samples = 4;
  const CameraFrame osmesa = render_with(s, "osmesa", all);
  const CameraFrame egl = render_with(s, "egl", all);
  expect_same_scene(osmesa, egl);
}

// MuJoCo loads its GL entry points once per process; renderers of both backends taking turns on
// one thread must each still draw into their own context
TEST(GlBackends, BackendsTakingTurnsOnOneThreadKeepTheirFrames) {
  ASSERT_NE(make_egl_or_explain(), nullptr);
  Scene s;
  CameraConfig config;
  config.camera = "chase";
  config.width_px = 320;
  config.height_px = 240;
  RendererOptions egl_options;
  egl_options.backend = "egl";
  CameraRenderer osmesa(s.m, {config});
  CameraRenderer egl(s.m, {config}, egl_options);
  CameraFrame first, second, third, fourth;
  osmesa.render(s.d, 0, &first);
  egl.render(s.d, 0, &second);
  osmesa.render(s.d, 0, &third);
  egl.render(s.d, 0, &fourth);
  EXPECT_EQ(first.pixels, third.pixels);
  EXPECT_EQ(second.pixels, fourth.pixels);
  expect_same_scene(first, second);
}

}  // namespace
}  // namespace uavsim::server::render
