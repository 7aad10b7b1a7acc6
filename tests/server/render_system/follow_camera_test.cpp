// --record-camera follow in the frame service: two quads of the MBZIRC 2020 world take off (a
// scripted run, as fast as possible, every frame kept); the directed overview camera keeps both in
// frame, a follow:uav0 camera shows uav0 at least kMinQuadPx across, and the overlay's text is
// burnt in.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "../sim/sim_fixture.hpp"
#include "app/camera_owners.hpp"
#include "app/hover_all.hpp"
#include "objects/world_objects.hpp"
#include "physics/world.hpp"
#include "render/camera_director.hpp"
#include "render/camera_setup.hpp"
#include "render/frame_service.hpp"
#include "render/overlay.hpp"
#include "sim/runner.hpp"
#include "sim/simulation.hpp"
#include "uavsim/common/pinhole.hpp"

namespace uavsim::server::render {
namespace {

constexpr double kRunS = 6.0;        // take-off at ~1 s, climbing to 5 m
constexpr double kQuadSpanM = 0.55;  // motor-to-motor diagonal (models/vehicles/quad.xml)
constexpr double kMinQuadPx = 20.0;  // follow:uav0 at >= 8 m: 579 px * 0.55 m / 8 m = 40 px at most
constexpr double kMinQuadFollowAllPx = 5.0;  // both quads, 20 m apart, in one 640 x 480 frame
constexpr int kMarginPx = 10;

struct Shot {
  double t_s = 0.0;
  Eigen::Vector3d position_enu_m;
  Eigen::Matrix3d R_enu_cam;
  std::vector<Eigen::Vector3d> vehicles;
  std::string rgb;
};

class Collector : public FrameConsumer {
 public:
  explicit Collector(int camera) : camera_(camera) {}
  void want(int camera, int64_t, int64_t, std::vector<EncodingKey>* e, bool* must) override {
    if (camera != camera_) return;
    e->push_back({Encoding::kRgb, 0});
    *must = true;  // deterministic: every frame
  }
  void dropped(int, int64_t) override {}
  void deliver(const ReadyFrame& f) override {
    if (f.camera != camera_) return;
    std::lock_guard<std::mutex> lock(mutex_);
    shots_.push_back(
        {f.stamp_s, f.position_enu_m, f.R_enu_cam, f.tracked_enu_m, *f.image({Encoding::kRgb, 0})});
  }
  std::vector<Shot> shots() {
    std::lock_guard<std::mutex> lock(mutex_);
    return shots_;
  }

 private:
  int camera_;
  std::mutex mutex_;
  std::vector<Shot> shots_;
};

// runs the scripted take-off of both quads with the overview camera directed by `params`
std::vector<Shot> fly(DirectorParams params, FrameCamera* camera_out) {
  const auto world = sim::testing::make_sim("mbzirc2020.xml");
  sim::Simulation& s = *world;
  objects::ObjectSet objects = objects::add_world_objects(s);
  const CameraOwners owners = app::camera_owners(s.world(), objects);
  std::vector<CameraSetup> cameras =
      discover_cameras(s.world().model(), owners, {}, 1.0 / s.control_dt_s());
  int overview = -1;
  for (size_t i = 0; i < cameras.size(); ++i) {
    if (cameras[i].config.camera == "overview") overview = static_cast<int>(i);
  }
  EXPECT_GE(overview, 0);
  Collector collector(overview);  // outlives the frame service
  FrameService frames(s.world().model(), cameras);
  const FrameCamera& cam = frames.cameras()[static_cast<size_t>(overview)];
  *camera_out = cam;
  params.fovy_deg = common::PinholeIntrinsics::fovy_deg_of(cam.height_px, cam.fy_px);
  params.aspect = static_cast<double>(cam.width_px) / cam.height_px;
  std::vector<int> bodies;
  for (const auto& v : s.world().vehicles()) bodies.push_back(v.body_id);
  frames.set_tracked_bodies(bodies);
  frames.set_director(overview, std::make_shared<CameraDirector>(params));
  frames.add_consumer(&collector);

  // both quads: GUIDED, arm, take off to 5 m once pre-arm passes (uavsim-server --hover 5)
  app::HoverAll hover(5.0, std::cout, /*quiet=*/true);
  s.schedule().add(sim::Phase::kPostControl, "launch", [&hover, &s] { hover.on_control_step(s); });
  sim::Runner runner(s, 0.0);
  runner.add_gate(sim::Phase::kCapture, "frames",
                  [&](double) { frames.capture(s.world().data()); });
  runner.run_until(kRunS);
  frames.wait_delivered();
  return collector.shots();
}

// the quad's apparent size: its span at its depth
double span_px(const FrameCamera& c, const Shot& shot, const Eigen::Vector3d& p) {
  const double depth = (shot.R_enu_cam.transpose() * (p - shot.position_enu_m)).z();
  return c.fx_px * kQuadSpanM / depth;
}

bool in_frame(const FrameCamera& c, const Shot& shot, const Eigen::Vector3d& p) {
  const auto px = project_to_pixel(c, shot.position_enu_m, shot.R_enu_cam, p);
  return px && px->x() >= kMarginPx && px->x() < c.width_px - kMarginPx && px->y() >= kMarginPx &&
         px->y() < c.height_px - kMarginPx;
}

TEST(FollowCamera, KeepsBothQuadsInFrameDuringTakeOff) {
  FrameCamera cam;
  const std::vector<Shot> shots = fly(DirectorParams{}, &cam);
  // 15 fps over 6 s, every frame kept
  ASSERT_GE(shots.size(), 89u);
  double max_z = 0.0;
  for (const Shot& shot : shots) {
    ASSERT_EQ(shot.vehicles.size(), 2u);
    for (const Eigen::Vector3d& v : shot.vehicles) {
      max_z = std::max(max_z, v.z());
      EXPECT_TRUE(in_frame(cam, shot, v)) << "t=" << shot.t_s << " " << v.transpose();
      EXPECT_GE(span_px(cam, shot, v), kMinQuadFollowAllPx) << "t=" << shot.t_s;
    }
  }
  EXPECT_GT(max_z, 3.0);  // they did take off
  // far closer than the fixed overview (0, -75, 45): about 90 m from the quads
  EXPECT_LT((shots.back().position_enu_m - shots.back().vehicles[0]).norm(), 60.0);
}

TEST(FollowCamera, FollowingOneQuadShowsItLargeAndTheOverlayIsBurntIn) {
  DirectorParams p;
  p.vehicle = 0;
  FrameCamera cam;
  const std::vector<Shot> shots = fly(p, &cam);
  ASSERT_GE(shots.size(), 89u);
  for (const Shot& shot : shots) {
    EXPECT_TRUE(in_frame(cam, shot, shot.vehicles[0])) << "t=" << shot.t_s;
    EXPECT_GE(span_px(cam, shot, shot.vehicles[0]), kMinQuadPx) << "t=" << shot.t_s;
  }
  // the overlay on the last frame: the time line and uav0's label change pixels
  const Shot& last = shots.back();
  OverlayInfo info;
  info.time_s = last.t_s;
  info.vehicles = {{"uav0", "GUIDED"}, {"uav1", "GUIDED"}};
  info.events = {{"1.0 s uav0 takeoff", 0}};
  std::string drawn = last.rgb;
  draw_overlay(info, cam, last.position_enu_m, last.R_enu_cam, last.vehicles,
               reinterpret_cast<uint8_t*>(drawn.data()));
  const PixelRect r = overlay_time_rect();
  int changed = 0;
  for (int y = r.y_px; y < r.y_px + r.height_px; ++y) {
    for (int x = r.x_px; x < r.x_px + r.width_px; ++x) {
      const size_t i = (static_cast<size_t>(y) * cam.width_px + x) * 3;
      changed += drawn[i] != last.rgb[i] || drawn[i + 1] != last.rgb[i + 1] ||
                 drawn[i + 2] != last.rgb[i + 2];
    }
  }
  EXPECT_GT(changed, 50);
  // uav0's label: right of its projection
  const auto px = project_to_pixel(cam, last.position_enu_m, last.R_enu_cam, last.vehicles[0]);
  ASSERT_TRUE(px);
  int label = 0;
  for (int y = static_cast<int>(px->y()) - 20; y < static_cast<int>(px->y()); ++y) {
    for (int x = static_cast<int>(px->x()) + 13;
         x < std::min(cam.width_px, static_cast<int>(px->x()) + 100); ++x) {
      if (y < 0 || y >= cam.height_px) continue;
      const size_t i = (static_cast<size_t>(y) * cam.width_px + x) * 3;
      label += drawn[i] != last.rgb[i];
    }
  }
  EXPECT_GT(label, 30);
}

}  // namespace
}  // namespace uavsim::server::render
