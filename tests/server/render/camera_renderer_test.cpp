#include "render/camera_renderer.hpp"

#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <memory>
#include <stdexcept>
#include <string>
#include <thread>

#include "pixel_blob.hpp"

namespace uavsim::server::render {
namespace {

constexpr double kPixelTol = 2.0;      // brief: centre and radius within 2 px
constexpr double kSubPixelTol = 0.25;  // rendered vs ray-cast silhouette centroid
constexpr double kAreaRelTol = 0.03;   // tessellated sphere (28 slices) vs true silhouette area
constexpr double kFocalTol_px = 1e-3;  // the expected focal lengths are given to 3 decimals
constexpr double kCentreTol_px = 1e-2;  // the projected centre against its hand-worked value
constexpr int kGreyTol = 1;             // one grey level of rounding

// One camera at (0, 0, 1) looking along world +x (its right is world -y, its up world +z), a green
// mocap ball and a green ball on a slide joint along world y. The headlight is pure ambient so that
// the ball is exactly (0, 255, 0) on a black background: no shading, no specular highlight.
constexpr char kWorldXml[] = R"(
<mujoco>
  <option gravity="0 0 0" timestep="0.01"/>
  <statistic extent="10" center="0 0 0"/>
  <visual>
    <global offwidth="640" offheight="480"/>
    <headlight ambient="1 1 1" diffuse="0 0 0" specular="0 0 0"/>
  </visual>
  <worldbody>
    <camera name="front" pos="0 0 1" xyaxes="0 -1 0 0 0 1" fovy="45"/>
    <camera name="back" pos="0 0 1" xyaxes="0 1 0 0 0 1" fovy="45"/>
    <body name="ball" mocap="true" pos="4 0 1">
      <geom type="sphere" size="0.25" rgba="0 1 0 1" contype="0" conaffinity="0"/>
    </body>
    <body name="slider" pos="6 -2 1">
      <joint name="slide" type="slide" axis="0 1 0"/>
      <geom type="sphere" size="0.2" rgba="0 1 0 1" mass="1" contype="0" conaffinity="0"/>
    </body>
  </worldbody>
</mujoco>
)";
constexpr double kBallRadiusM = 0.25;
constexpr double kSliderSpeedMS =
    20.0;  // 0.2 m per 10 ms step: 19 px at 6 m, so a one-step lag shows

struct ModelDeleter {
  void operator()(mjModel* m) const { mj_deleteModel(m); }
};
struct DataDeleter {
  void operator()(mjData* d) const { mj_deleteData(d); }
};
using ModelPtr = std::unique_ptr<mjModel, ModelDeleter>;
using DataPtr = std::unique_ptr<mjData, DataDeleter>;

ModelPtr load_model(const std::string& xml, const std::string& file_name) {
  const std::string path = ::testing::TempDir() + file_name;
  std::ofstream(path) << xml;
  char error[1000] = "";
  ModelPtr m(mj_loadXML(path.c_str(), nullptr, error, sizeof(error)));
  EXPECT_NE(m, nullptr) << error;
  return m;
}

using testing::Blob;
using testing::project;

// pixels of the green ball: centroid and the radius of the disc of equal area
Blob find_green(const CameraFrame& f) {
  return testing::find_blob(f, [](int r, int g, int b) { return g > 128 && r < 64 && b < 64; });
}

// the silhouette of a true sphere, ray-cast through every pixel centre with the frame's pose and
// intrinsics
Blob raycast_sphere(const CameraFrame& f, const Eigen::Vector3d& centre_enu, double radius_m) {
  const CameraIntrinsics& k = f.intrinsics;
  const Eigen::Vector3d to_centre_cam = f.R_enu_cam.transpose() * (centre_enu - f.position_enu_m);
  Blob b;
  for (int v = 0; v < f.height_px; ++v) {
    for (int u = 0; u < f.width_px; ++u) {
      const Eigen::Vector3d ray =
          Eigen::Vector3d((u - k.cx_px) / k.fx_px, (v - k.cy_px) / k.fy_px, 1.0).normalized();
      // the ray hits when its distance from the centre is at most the radius
      const double along = ray.dot(to_centre_cam);
      if (along > 0 && (to_centre_cam - along * ray).squaredNorm() <= radius_m * radius_m) {
        b.u += u;
        b.v += v;
        b.area_px += 1.0;
      }
    }
  }
  b.u /= b.area_px;
  b.v /= b.area_px;
  return b;
}

CameraConfig camera(const std::string& name, int width_px, int height_px) {
  CameraConfig c;
  c.camera = name;
  c.width_px = width_px;
  c.height_px = height_px;
  return c;
}

class CameraRendererTest : public ::testing::Test {
 protected:
  void SetUp() override {
    m_ = load_model(kWorldXml, "camera_renderer_test.xml");
    ASSERT_NE(m_, nullptr);
    d_.reset(mj_makeData(m_.get()));
    ball_mocap_ = m_->body_mocapid[mj_name2id(m_.get(), mjOBJ_BODY, "ball")];
    slider_body_ = mj_name2id(m_.get(), mjOBJ_BODY, "slider");
  }

  // put the ball there (hide the slider far behind the camera) and forward the data
  void place_ball(const Eigen::Vector3d& p_enu) {
    for (int i = 0; i < 3; ++i) d_->mocap_pos[3 * ball_mocap_ + i] = p_enu[i];
    d_->qpos[0] = 100.0;
    mj_forward(m_.get(), d_.get());
  }

  ModelPtr m_;
  DataPtr d_;
  int ball_mocap_ = -1;
  int slider_body_ = -1;
};

TEST_F(CameraRendererTest, IntrinsicsFollowMujocosVerticalFovy) {
  // fy = (h/2) / tan(fovy/2) = 240 / tan(22.5 deg) = 579.41 px; square pixels; centre (w-1)/2,
  // (h-1)/2
  const CameraIntrinsics k = CameraIntrinsics::from_fovy_deg(640, 480, 45.0);
  EXPECT_NEAR(k.fy_px, 579.411, kFocalTol_px);
  EXPECT_DOUBLE_EQ(k.fx_px, k.fy_px);
  EXPECT_DOUBLE_EQ(k.cx_px, 319.5);
  EXPECT_DOUBLE_EQ(k.cy_px, 239.5);
}

TEST_F(CameraRendererTest, PoseIsInOpencvCameraConvention) {
  CameraRenderer renderer(m_.get(), {camera("front", 64, 48)});
  place_ball({4, 0, 1});
  CameraFrame f;
  renderer.render(d_.get(), 0, &f);
  // "front" looks along world +x, its right is world -y and image down is world -z
  EXPECT_TRUE(f.position_enu_m.isApprox(Eigen::Vector3d(0, 0, 1)));
  EXPECT_TRUE(f.R_enu_cam.col(0).isApprox(Eigen::Vector3d(0, -1, 0), 1e-9));
  EXPECT_TRUE(f.R_enu_cam.col(1).isApprox(Eigen::Vector3d(0, 0, -1), 1e-9));
  EXPECT_TRUE(f.R_enu_cam.col(2).isApprox(Eigen::Vector3d(1, 0, 0), 1e-9));
  EXPECT_EQ(f.camera_name, "front");
  EXPECT_EQ(f.camera_id, mj_name2id(m_.get(), mjOBJ_CAMERA, "front"));
}

TEST_F(CameraRendererTest, BallOnAxisAppearsAtPrincipalPointWithPredictedRadius) {
  CameraRenderer renderer(m_.get(), {camera("front", 640, 480)});
  const Eigen::Vector3d centre(4, 0, 1);
  place_ball(centre);
  CameraFrame f;
  renderer.render(d_.get(), 0, &f);
  const Blob seen = find_green(f);
  ASSERT_GT(seen.area_px, 0);

  // on the axis at D = 4 m: radius = fy * r / sqrt(D^2 - r^2) = 579.41 * 0.25 / 3.992 = 36.29 px
  const double predicted_radius_px = f.intrinsics.fy_px * kBallRadiusM / std::sqrt(16.0 - 0.0625);
  EXPECT_NEAR(seen.u, f.intrinsics.cx_px, kPixelTol);
  EXPECT_NEAR(seen.v, f.intrinsics.cy_px, kPixelTol);
  EXPECT_NEAR(seen.radius_px(), predicted_radius_px, kPixelTol);

  // the pixel-centre convention, sub-pixel: a centred disc's centroid is the principal point, which
  // is (319.5, 239.5) in OpenCV pixels, not (320, 240)
  EXPECT_NEAR(seen.u, 319.5, kSubPixelTol);
  EXPECT_NEAR(seen.v, 239.5, kSubPixelTol);
}

TEST_F(CameraRendererTest, BallOffCentreAppearsWhereIntrinsicsPredict) {
  CameraRenderer renderer(m_.get(), {camera("front", 640, 480)});
  // 0.9 m left of and 0.6 m above the axis at 4 m: about 13 and 8.5 degrees off
  const Eigen::Vector3d centre(4, 0.9, 1.6);
  place_ball(centre);
  CameraFrame f;
  renderer.render(d_.get(), 0, &f);
  const Blob seen = find_green(f);
  ASSERT_GT(seen.area_px, 0);

  // left and up in the image: u = cx - fx * 0.9/4 = 189.1, v = cy - fy * 0.6/4 = 152.6
  const Eigen::Vector2d centre_px = project(f, centre);
  EXPECT_NEAR(centre_px.x(), 319.5 - 579.411 * 0.9 / 4.0, kCentreTol_px);
  EXPECT_NEAR(centre_px.y(), 239.5 - 579.411 * 0.6 / 4.0, kCentreTol_px);
  EXPECT_NEAR(seen.u, centre_px.x(), kPixelTol);
  EXPECT_NEAR(seen.v, centre_px.y(), kPixelTol);
  // off the axis by theta the ball is an ellipse (alpha: its angular radius, sin(alpha) = r/D):
  //   radial semi-axis a = f sin(alpha) cos(alpha) / (cos^2(theta) - sin^2(alpha)) = 37.59 px
  //   tangential b = f sin(alpha) / sqrt(cos^2(theta) - sin^2(alpha)) = 36.28 px; equal-area
  //   radius 36.93 px
  const Eigen::Vector3d to_centre = f.R_enu_cam.transpose() * (centre - f.position_enu_m);
  const double sin_a = kBallRadiusM / to_centre.norm();
  const double cos_t = to_centre.z() / to_centre.norm();
  const double fy = f.intrinsics.fy_px;
  const double conic = cos_t * cos_t - sin_a * sin_a;
  const double a_px = fy * sin_a * std::sqrt(1 - sin_a * sin_a) / conic;
  const double b_px = fy * sin_a / std::sqrt(conic);
  EXPECT_NEAR(seen.radius_px(), std::sqrt(a_px * b_px), kPixelTol);

  // the whole silhouette agrees with a ray-cast through the stated pose and intrinsics
  const Blob cast = raycast_sphere(f, centre, kBallRadiusM);
  EXPECT_NEAR(seen.u, cast.u, kSubPixelTol);
  EXPECT_NEAR(seen.v, cast.v, kSubPixelTol);
  EXPECT_NEAR(seen.area_px, cast.area_px, kAreaRelTol * cast.area_px);
}

TEST_F(CameraRendererTest, FovyOverrideChangesFocalLength) {
  CameraConfig wide = camera("front", 320, 240);
  wide.fovy_deg = 60.0;
  CameraRenderer renderer(m_.get(), {wide});
  // fy = 120 / tan(30 deg) = 207.85 px
  EXPECT_NEAR(renderer.intrinsics(0).fy_px, 207.846, kFocalTol_px);
  const Eigen::Vector3d centre(4, -0.7, 0.5);
  place_ball(centre);
  CameraFrame f;
  renderer.render(d_.get(), 0, &f);
  const Blob seen = find_green(f);
  const Blob cast = raycast_sphere(f, centre, kBallRadiusM);
  EXPECT_NEAR(seen.u, cast.u, kSubPixelTol);
  EXPECT_NEAR(seen.v, cast.v, kSubPixelTol);
  EXPECT_NEAR(seen.area_px, cast.area_px, kAreaRelTol * cast.area_px);
}

TEST_F(CameraRendererTest, ObjectAboveAxisIsInTopHalf) {
  CameraRenderer renderer(m_.get(), {camera("front", 320, 240)});
  place_ball({4, 0, 2});  // 1 m above the camera
  CameraFrame f;
  renderer.render(d_.get(), 0, &f);
  const Blob seen = find_green(f);
  ASSERT_GT(seen.area_px, 0);
  EXPECT_LT(seen.v, f.intrinsics.cy_px - 50);  // v = cy - fy * 1/4 = 119.5 - 72.4
  // and nothing green in the bottom half
  for (int v = f.height_px / 2; v < f.height_px; ++v) {
    for (int u = 0; u < f.width_px; ++u) {
      ASSERT_LT(f.pixels[(static_cast<size_t>(v) * f.width_px + u) * 3 + 1], 128) << u << "," << v;
    }
  }
}

TEST_F(CameraRendererTest, StampIsTheTimeOfThePoseShown) {
  CameraRenderer renderer(m_.get(), {camera("front", 640, 480)});
  d_->mocap_pos[3 * ball_mocap_ + 2] = -100.0;  // ball out of sight
  d_->qvel[0] = kSliderSpeedMS;
  mj_forward(m_.get(), d_.get());
  CameraFrame f;
  for (int frame = 0; frame < 5; ++frame) {
    renderer.render(d_.get(), 0, &f);
    EXPECT_EQ(f.stamp_us, std::llround(d_->time * 1e6));
    EXPECT_EQ(f.stamp_us, frame * 40000);  // 4 steps of 10 ms between frames
    // no gravity, no damping: y(t) = -2 + 20 t exactly; the ball must be where it is at the stamp
    const Eigen::Vector3d centre(6.0, -2.0 + kSliderSpeedMS * f.stamp_us * 1e-6, 1.0);
    const Blob seen = find_green(f);
    ASSERT_GT(seen.area_px, 0) << "frame " << frame;
    EXPECT_NEAR(seen.u, project(f, centre).x(), kPixelTol) << "frame " << frame;
    EXPECT_NEAR(seen.v, project(f, centre).y(), kPixelTol) << "frame " << frame;
    // step, then forward as the render contract asks (mj_step leaves positions one step behind
    // d->time)
    for (int i = 0; i < 4; ++i) mj_step(m_.get(), d_.get());
    mj_forward(m_.get(), d_.get());
  }
}

TEST_F(CameraRendererTest, GreyIsBt601Luma) {
  CameraConfig grey = camera("front", 320, 240);
  grey.format = PixelFormat::kGrey8;
  CameraRenderer renderer(m_.get(), {grey});
  place_ball({4, 0, 1});
  CameraFrame f;
  renderer.render(d_.get(), 0, &f);
  ASSERT_EQ(f.pixels.size(), 320u * 240u);
  // pure green: Y = 0.587 * 255 = 149.7; background black
  EXPECT_NEAR(f.pixels[120 * 320 + 160], 150, kGreyTol);
  EXPECT_EQ(f.pixels[0], 0);
}

TEST_F(CameraRendererTest, ServesSeveralCamerasWithTheirOwnSettings) {
  CameraConfig smooth_front = camera("front", 640, 480);
  smooth_front.flags.msaa_samples = 4;
  CameraRenderer renderer(m_.get(),
                          {camera("front", 320, 240), camera("back", 160, 120), smooth_front});
  ASSERT_EQ(renderer.camera_count(), 3);
  EXPECT_EQ(renderer.find("back"), 1);
  EXPECT_EQ(renderer.find("side"), std::nullopt);
  place_ball({4, 0, 1});
  CameraFrame front, back, smooth;
  renderer.render(d_.get(), 0, &front);
  renderer.render(d_.get(), 1, &back);
  renderer.render(d_.get(), 2, &smooth);
  EXPECT_GT(find_green(front).area_px, 0);
  EXPECT_EQ(back.width_px, 160);
  EXPECT_EQ(find_green(back).area_px, 0);  // looks away from the ball
  // multisampled: same place, anti-aliased edge
  const Blob seen = find_green(smooth);
  EXPECT_NEAR(seen.u, 319.5, kPixelTol);
  EXPECT_NEAR(seen.v, 239.5, kPixelTol);
}

TEST_F(CameraRendererTest, FramesFallDueAtTheirRate) {
  CameraConfig slow = camera("front", 32, 24);
  slow.fps_hz = 10.0;
  CameraRenderer renderer(m_.get(), {slow});
  CameraFrame f;
  EXPECT_TRUE(renderer.due(d_.get(), 0));  // first frame at once
  renderer.render(d_.get(), 0, &f);
  d_->time = 0.05;
  EXPECT_FALSE(renderer.due(d_.get(), 0));
  d_->time = 0.1;  // period 100 ms
  EXPECT_TRUE(renderer.due(d_.get(), 0));
}

TEST_F(CameraRendererTest, UnknownCameraFailsNamingIt) {
  try {
    CameraRenderer renderer(m_.get(), {camera("down", 64, 48)});
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("'down'"), std::string::npos) << e.what();
  }
}

TEST_F(CameraRendererTest, OversizeRequestFailsNamingTheOffscreenSizeNeeded) {
  try {
    CameraRenderer renderer(m_.get(), {camera("front", 1280, 720)});
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("'front'"), std::string::npos) << what;
    EXPECT_NE(what.find("offwidth=\"1280\" offheight=\"720\""), std::string::npos) << what;
  }
  const OffscreenSize need =
      required_offscreen_size({camera("front", 1280, 720), camera("back", 640, 960)});
  EXPECT_EQ(need.width_px, 1280);
  EXPECT_EQ(need.height_px, 960);
}

TEST_F(CameraRendererTest, RenderersOnTwoThreadsRenderTheSameImage) {
  place_ball({4, 0.9, 1.6});
  // each renderer thread: its own renderer (GL context) and its own copy of the data
  CameraFrame frames[2];
  auto render_on_thread = [&](CameraFrame* out) {
    mjData* d = mj_copyData(nullptr, m_.get(), d_.get());
    CameraRenderer renderer(m_.get(), {camera("front", 320, 240)});
    for (int i = 0; i < 3; ++i) renderer.render(d, 0, out);
    mj_deleteData(d);
  };
  std::thread a(render_on_thread, &frames[0]);
  std::thread b(render_on_thread, &frames[1]);
  a.join();
  b.join();
  EXPECT_GT(find_green(frames[0]).area_px, 100);
  EXPECT_EQ(frames[0].pixels, frames[1].pixels);
}

TEST_F(CameraRendererTest, RendersWithNoDisplay) {
  unsetenv("DISPLAY");
  unsetenv("WAYLAND_DISPLAY");
  CameraRenderer renderer(m_.get(), {camera("front", 320, 240)});
  place_ball({4, 0, 1});
  CameraFrame f;
  renderer.render(d_.get(), 0, &f);
  EXPECT_GT(find_green(f).area_px, 100);
}

}  // namespace
}  // namespace uavsim::server::render
