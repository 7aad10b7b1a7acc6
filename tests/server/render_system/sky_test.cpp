// The MBZIRC worlds' onboard cameras see the sky that models/common/ground.xml defines (a gradient
// skybox, light blue to near white), not black: each world turns the skybox on for them (cameras
// render with every effect off unless the world asks, render/camera_setup.hpp). Each camera is
// lifted to 10 m (clear of its vehicle) and pitched 60 deg up, and rendered with the configuration
// the server would give it.
#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <string>

#include "physics/world.hpp"
#include "render/camera_renderer.hpp"
#include "render/camera_setup.hpp"
#include "uavsim/common/angles.hpp"

namespace uavsim::server::render::testing {
namespace {

// ground.xml's sky: rgb1 0.55 0.7 0.9 (140 178 230) to rgb2 0.9 0.95 1 (230 242 255); lit or not,
// its pixels are bright and blue-tinted; black (the skybox off) is 0 0 0
constexpr double kMinSkyMean = 100.0;

struct Mean {
  double r = 0, g = 0, b = 0;
};

Mean mean_rgb(const CameraFrame& f) {
  Mean m;
  const size_t n = static_cast<size_t>(f.width_px) * f.height_px;
  for (size_t i = 0; i < n; ++i) {
    m.r += f.pixels[3 * i];
    m.g += f.pixels[3 * i + 1];
    m.b += f.pixels[3 * i + 2];
  }
  m.r /= n;
  m.g /= n;
  m.b /= n;
  return m;
}

void expect_sky(const std::string& world_file, const std::string& camera, const std::string& body) {
  SCOPED_TRACE(world_file + " " + camera);
  physics::ComposeOptions co;
  co.models_dir = UAVSIM_MODELS_DIR;
  const auto world =
      physics::World::load(std::string(UAVSIM_MODELS_DIR) + "/worlds/" + world_file, co);
  mjModel* m = world->mutable_model();
  std::vector<CameraConfig> configs;
  for (const CameraSetup& s : discover_cameras(m, CameraOwners{}, {}, 100.0)) {
    if (s.config.camera == camera) configs.push_back(s.config);
  }
  ASSERT_EQ(configs.size(), 1u);
  EXPECT_TRUE(configs[0].flags.skybox);
  configs[0].width_px = 96;  // the sky is uniform enough: a small frame is quick
  configs[0].height_px = 64;
  const OffscreenSize need = required_offscreen_size(configs);
  m->vis.global.offwidth = std::max(m->vis.global.offwidth, need.width_px);
  m->vis.global.offheight = std::max(m->vis.global.offheight, need.height_px);

  // the camera's mocap gimbal at 10 m, pitched 60 deg up (the camera looks along the body's +x)
  const int id = mj_name2id(m, mjOBJ_BODY, body.c_str());
  ASSERT_GE(id, 0);
  const int mocap = m->body_mocapid[id];
  ASSERT_GE(mocap, 0);
  mjData* d = mj_makeData(m);
  const Eigen::Quaterniond up(Eigen::AngleAxisd(-common::kPi / 3, Eigen::Vector3d::UnitY()));
  d->mocap_pos[3 * mocap + 2] = 10.0;
  d->mocap_quat[4 * mocap + 0] = up.w();
  d->mocap_quat[4 * mocap + 1] = up.x();
  d->mocap_quat[4 * mocap + 2] = up.y();
  d->mocap_quat[4 * mocap + 3] = up.z();
  mj_forward(m, d);
  {
    CameraRenderer renderer(m, configs);
    CameraFrame f;
    renderer.render(d, 0, &f);
    ASSERT_EQ(f.pixels.size(), 96u * 64u * 3u);
    const Mean s = mean_rgb(f);
    EXPECT_GT((s.r + s.g + s.b) / 3.0, kMinSkyMean) << s.r << " " << s.g << " " << s.b;
    EXPECT_GE(s.b, s.r) << "a blue-tinted sky";
  }
  mj_deleteData(d);
}

TEST(Sky, Mbzirc2017DownCameraPitchedUpSeesTheSky) {
  expect_sky("mbzirc2017.xml", "uav0_down", "uav0_gimbal");
}

TEST(Sky, Mbzirc2020FrontCamerasPitchedUpSeeTheSky) {
  expect_sky("mbzirc2020.xml", "uav0_front", "uav0_gimbal");
  expect_sky("mbzirc2020_field.xml", "uav1_front", "uav1_gimbal");
}

}  // namespace
}  // namespace uavsim::server::render::testing
