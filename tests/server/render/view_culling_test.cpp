// Geoms outside a camera's view leave its scene before MuJoCo draws it (render/view_culling.hpp):
// exactly those whose bounding sphere lies outside the frustum go, and the frames stay the same to
// the bit.
#include "render/view_culling.hpp"

#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include <set>
#include <string>

#include "../../support/mjcf_scene.hpp"
#include "render/camera_renderer.hpp"

namespace uavsim::server::render {
namespace {

// One camera at (0, 0, 1) looking along +x (its left is +y), 45 degrees vertical field of view; at
// 320 x 240 the view at x = 5 m spans y in [-2.76, 2.76] and z in [1 - 2.07, 1 + 2.07]. The near
// plane is at 0.01 x the extent, 0.1 m.
constexpr char kSceneXml[] = R"(
<mujoco>
  <statistic extent="10" center="0 0 1"/>
  <visual><global offwidth="320" offheight="240"/><quality shadowsize="1024"/></visual>
  <asset>
    <texture name="grid" type="2d" builtin="checker" rgb1="0.5 0.5 0.4" rgb2="0.4 0.4 0.3" width="64" height="64"/>
    <material name="ground" texture="grid" texrepeat="20 20"/>
  </asset>
  <worldbody>
    <light directional="true" pos="0 0 20" dir="0 0 -1" castshadow="true"/>
    <camera name="eye" pos="0 0 1" xyaxes="0 -1 0 0 0 1" fovy="45"/>
    <geom name="ground" type="plane" size="50 50 5" material="ground"/>
    <geom name="ahead" type="sphere" pos="5 0 1" size="0.3" rgba="0 0.8 0 1"/>
    <geom name="edge" type="sphere" pos="5 2.9 1" size="0.3" rgba="0.8 0 0 1"/>
    <geom name="near_corner" type="box" pos="3 -1.5 0.2" size="0.2 0.2 0.2" rgba="0 0 0.8 1"/>
    <geom name="big_behind" type="sphere" pos="-3 0 1" size="3.5" rgba="0.8 0.8 0 0.5"/>
    <geom name="behind" type="sphere" pos="-5 0 1" size="0.3" rgba="0.8 0 0.8 1"/>
    <geom name="far_left" type="box" pos="5 8 1" size="0.2 0.2 0.2" rgba="0 0.8 0.8 1"/>
    <geom name="above" type="capsule" pos="5 0 6" size="0.1 0.3" rgba="0.5 0.5 0.5 1"/>
    <geom name="before_near" type="sphere" pos="0.03 0 1" size="0.01" rgba="1 1 1 1"/>
    <site name="marker" pos="-2 0 1" size="0.1"/>
    <body name="shade" mocap="true" pos="4 0 6">
      <geom name="shade" type="box" size="1 1 0.05" rgba="0.3 0.3 0.3 1"/>
    </body>
  </worldbody>
</mujoco>
)";

struct Scene : uavsim::testing::MjcfScene {
  Scene() : MjcfScene(kSceneXml, ::testing::TempDir() + "view_culling_scene.xml") {}
};

// the names of the scene's model geoms, and "site" for each site, after culling for the camera
std::set<std::string> kept_after_culling(const Scene& s, int width_px, int height_px) {
  mjvOption opt;
  mjv_defaultOption(&opt);
  mjvScene scn;
  mjv_defaultScene(&scn);
  mjv_makeScene(s.m, &scn, 1000);
  mjvCamera view;
  mjv_defaultCamera(&view);
  view.type = mjCAMERA_FIXED;
  view.fixedcamid = mj_name2id(s.m, mjOBJ_CAMERA, "eye");
  mjv_updateScene(s.m, s.d, &opt, nullptr, &view, mjCAT_ALL, &scn);
  const int before = scn.ngeom;
  const int removed = remove_geoms_outside_view(s.m, width_px, height_px, &scn);
  EXPECT_EQ(scn.ngeom, before - removed);
  std::set<std::string> names;
  for (int i = 0; i < scn.ngeom; ++i) {
    const mjvGeom& g = scn.geoms[i];
    if (g.objtype == mjOBJ_GEOM) {
      names.insert(mj_id2name(s.m, mjOBJ_GEOM, g.objid));
    } else if (g.objtype == mjOBJ_SITE) {
      names.insert("site");
    }
  }
  mjv_freeScene(&scn);
  return names;
}

TEST(ViewCulling, KeepsExactlyTheGeomsThatCanShow) {
  Scene s;
  const std::set<std::string> expected = {
      "ground",       // planes always stay
      "ahead",        // in the middle of the view
      "edge",         // its centre 0.14 m past the left edge, its radius 0.3 m: partly in view
      "near_corner",  // low and to the right, inside
      "big_behind",   // its centre behind the camera, its surface in front of it
      "site",         // decor always stays
  };
  EXPECT_EQ(kept_after_culling(s, 320, 240), expected);
}

TEST(ViewCulling, TheViewportsAspectRatioSetsTheSides) {
  // the same camera at 120 x 240 sees a third of the width: y in [-1.04, 1.04] at 5 m, so the
  // sphere at 2.9 m to the left and the box at 1.5 m to the right leave too
  Scene s;
  const std::set<std::string> kept = kept_after_culling(s, 120, 240);
  EXPECT_TRUE(kept.count("ahead"));
  EXPECT_FALSE(kept.count("edge"));
  EXPECT_FALSE(kept.count("near_corner"));
}

CameraConfig eye(bool shadows) {
  CameraConfig c;
  c.camera = "eye";
  c.width_px = 320;
  c.height_px = 240;
  c.flags.shadows = shadows;
  c.modalities.depth = true;
  c.modalities.segmentation = true;
  return c;
}

CameraFrame render(const Scene& s, bool cull, bool shadows) {
  RendererOptions options;
  options.cull_outside_view = cull;
  CameraRenderer renderer(s.m, {eye(shadows)}, options);
  CameraFrame frame;
  RenderPasses passes;
  passes.depth = true;
  passes.segmentation = true;
  renderer.render(s.d, 0, passes, &frame);
  return frame;
}

TEST(ViewCulling, FramesAreTheSameToTheBit) {
  Scene s;
  const CameraFrame all = render(s, false, false);
  const CameraFrame culled = render(s, true, false);
  EXPECT_EQ(all.pixels, culled.pixels);
  ASSERT_EQ(all.depth_m.size(), culled.depth_m.size());
  for (size_t i = 0; i < all.depth_m.size(); ++i) {
    // NaN where nothing was hit, in both
    ASSERT_TRUE(all.depth_m[i] == culled.depth_m[i] ||
                (std::isnan(all.depth_m[i]) && std::isnan(culled.depth_m[i])))
        << "pixel " << i;
  }
  EXPECT_EQ(all.geom_ids, culled.geom_ids);
}

TEST(ViewCulling, WithShadowsWhatTheViewCannotSeeStillCastsItsShadow) {
  // the "shade" box is above the view (culled without shadows: the test above) and its shadow falls
  // on the ground ahead: moved away, the frame changes, so with shadows the scene kept it
  Scene s;
  const CameraFrame with_shade = render(s, true, true);
  const int shade = s.m->body_mocapid[mj_name2id(s.m, mjOBJ_BODY, "shade")];
  s.d->mocap_pos[3 * shade + 2] = 500.0;
  mj_forward(s.m, s.d);
  const CameraFrame without = render(s, true, true);
  EXPECT_NE(with_shade.pixels, without.pixels);
}

}  // namespace
}  // namespace uavsim::server::render
