// The shared ground (models/common/ground.xml) and what its render grid costs. MuJoCo draws a plane
// as a grid of quads whose spacing is the plane's third size value (capped at 200 x 200 quads), so
// that per-vertex lighting can vary across it. The ground is lit only by directional lights (the
// sun and MuJoCo's headlight), under which a coarse grid shades the ground as the finest one does;
// the finest grid, on a CPU renderer, was most of a 384 x 216 camera frame's time. These tests hold
// the shipped ground to the frames the finest grid renders.
#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>

#include "../../support/mjcf_scene.hpp"
#include "pixel_blob.hpp"
#include "render/camera_renderer.hpp"
#include "render/plane_grid.hpp"

namespace uavsim::server::render {
namespace {

// The bounds the GL backends are held to (gl_backend_test.cpp): rasterisation noise, nothing more.
constexpr double kMeanAbsDiffTol = 1.0;       // grey levels, mean over all pixels and channels
constexpr double kDifferentPixelsTol = 0.01;  // fraction of pixels off by more than kLargeDiff
constexpr int kLargeDiff = 24;                // grey levels in any channel
constexpr double kCentroidTol = 0.25;         // px between the two frames' balloon centroids
constexpr double kFinestSpacingM = 0.1;       // below 1000 m / 198: MuJoCo's 200 x 200 quads

// A green balloon on a pole over the shared ground, seen by the cameras the missions fly with: a
// forward camera at take-off height pitched a little down (MBZIRC 2020's 384 x 216, 22 degrees),
// a downward camera at 8 m (MBZIRC 2017's 384 x 168, 65 degrees) and an oblique one at 9 m.
constexpr char kSceneXml[] = R"(
<mujoco>
  <visual><global offwidth="384" offheight="216"/></visual>
  <include file="ground.xml"/>
  <worldbody>
    <camera name="front" pos="0 -12 2.5" xyaxes="1 0 0 0 0.1 1" fovy="22"/>
    <camera name="down" pos="1 1 8" xyaxes="0 -1 0 1 0 0" fovy="65"/>
    <camera name="oblique" pos="-7 -7 9" xyaxes="0.707 -0.707 0 0.4 0.4 0.825" fovy="45"/>
    <body name="balloon" pos="0 0 0">
      <geom type="cylinder" fromto="0 0 0 0 0 2.6" size="0.03" rgba="0.6 0.6 0.6 1"/>
      <geom type="sphere" pos="0 0 3" size="0.3" rgba="0.1 0.8 0.1 1"/>
    </body>
  </worldbody>
</mujoco>
)";

// The scene beside a copy of the shipped ground: MuJoCo resolves <include> relative to the model
// file's directory only.
struct Scene : uavsim::testing::MjcfScene {
  static std::string with_ground_copy(const std::string& name) {
    std::ifstream in(std::string(UAVSIM_MODELS_DIR) + "/common/ground.xml");
    std::stringstream text;
    text << in.rdbuf();
    std::ofstream(::testing::TempDir() + "ground.xml") << text.str();
    return ::testing::TempDir() + name;
  }
  Scene() : MjcfScene(kSceneXml, with_ground_copy("ground_grid_scene.xml")) {}
};

int ground_geom(const mjModel* m) { return mj_name2id(m, mjOBJ_GEOM, "ground"); }

CameraFrame render(Scene& s, const std::string& camera, int width_px, int height_px,
                   double spacing_m) {
  s.m->geom_size[3 * ground_geom(s.m) + 2] = spacing_m;  // read when the GL context is made
  CameraConfig config;
  config.camera = camera;
  config.width_px = width_px;
  config.height_px = height_px;
  config.flags.skybox = true;  // as the missions' worlds ask
  CameraRenderer renderer(s.m, {config});
  CameraFrame frame;
  renderer.render(s.d, 0, &frame);
  return frame;
}

void expect_same_frame(const CameraFrame& finest, const CameraFrame& shipped) {
  ASSERT_EQ(finest.pixels.size(), shipped.pixels.size());
  const testing::FrameDifference diff = testing::frame_difference(finest, shipped, kLargeDiff);
  ::testing::Test::RecordProperty("mean_abs_diff", std::to_string(diff.mean_abs_diff));
  ::testing::Test::RecordProperty("pixels_off", std::to_string(diff.large_pixels));
  EXPECT_LE(diff.mean_abs_diff, kMeanAbsDiffTol);
  EXPECT_LE(diff.large_fraction, kDifferentPixelsTol);

  const auto green = [](int r, int g, int b) { return g > 100 && g > 2 * r && g > 2 * b; };
  const testing::Blob a = testing::find_blob(finest, green);
  const testing::Blob b = testing::find_blob(shipped, green);
  ASSERT_GT(a.area_px, 20.0) << "the camera does not see the balloon";
  EXPECT_NEAR(a.u, b.u, kCentroidTol);
  EXPECT_NEAR(a.v, b.v, kCentroidTol);
  EXPECT_EQ(a.area_px, b.area_px);
}

TEST(GroundGrid, TheShippedGroundIsACoarseGrid) {
  Scene s;
  const int g = ground_geom(s.m);
  ASSERT_GE(g, 0);
  const double half_m = s.m->geom_size[3 * g];
  const int shipped = plane_grid_quads_per_side(half_m, s.m->geom_size[3 * g + 2]);
  EXPECT_EQ(plane_grid_quads_per_side(half_m, kFinestSpacingM), kMaxPlaneGridQuads);
  // a few hundred quads a frame, not 40000; and no warning for it at start-up
  EXPECT_LE(shipped * shipped, 1000) << shipped << " x " << shipped << " quads";
  EXPECT_TRUE(dense_plane_grid_warnings(s.m).empty());
}

TEST(GroundGrid, QuadsPerSideFollowMuJoCosRule) {
  EXPECT_EQ(plane_grid_quads_per_side(500, 50), 12);   // 10, even, plus two pads
  EXPECT_EQ(plane_grid_quads_per_side(500, 30), 18);   // 16 (of 16.7), plus two pads
  EXPECT_EQ(plane_grid_quads_per_side(30, 0.1), 200);  // capped: spacing at least 30 / 198
  EXPECT_EQ(plane_grid_quads_per_side(0, 1), kMaxPlaneGridQuads);  // an infinite side
  // sizes that never reach a loop or a cast as they are
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_EQ(plane_grid_quads_per_side(500, nan), kMaxPlaneGridQuads);
  EXPECT_EQ(plane_grid_quads_per_side(nan, 1), kMaxPlaneGridQuads);
  EXPECT_EQ(plane_grid_quads_per_side(inf, 1), kMaxPlaneGridQuads);
  EXPECT_EQ(plane_grid_quads_per_side(500, inf), 2);  // all pad
}

TEST(GroundGrid, ADenseGridIsNamedWithTheSpacingThatFixesIt) {
  Scene s;
  const int g = ground_geom(s.m);
  s.m->geom_size[3 * g + 2] = kFinestSpacingM;
  const std::vector<std::string> lines = dense_plane_grid_warnings(s.m);
  ASSERT_EQ(lines.size(), 1u);
  EXPECT_NE(lines[0].find("'ground' is drawn as 200 x 200 quads"), std::string::npos) << lines[0];
  EXPECT_NE(lines[0].find("a spacing of 25 m"), std::string::npos) << lines[0];
  s.m->geom_size[3 * g + 2] = 25;
  EXPECT_TRUE(dense_plane_grid_warnings(s.m).empty());
}

class GroundGridCamera : public ::testing::TestWithParam<const char*> {};

TEST_P(GroundGridCamera, RendersTheFramesOfTheFinestGrid) {
  Scene s;
  const int g = ground_geom(s.m);
  ASSERT_GE(g, 0);
  const double shipped_m = s.m->geom_size[3 * g + 2];
  const std::string camera = GetParam();
  const int height_px = camera == "down" ? 168 : 216;
  const CameraFrame finest = render(s, camera, 384, height_px, kFinestSpacingM);
  const CameraFrame shipped = render(s, camera, 384, height_px, shipped_m);
  expect_same_frame(finest, shipped);
}

INSTANTIATE_TEST_SUITE_P(MissionCameras, GroundGridCamera,
                         ::testing::Values("front", "down", "oblique"));

}  // namespace
}  // namespace uavsim::server::render
