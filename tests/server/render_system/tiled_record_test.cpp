// --record-layout tiled: the recorder composes the main view and the vehicles' onboard cameras
// (tile_layout). A second of the MBZIRC 2020 world, every frame kept: each composed frame holds the
// overview's frame of its instant on the left and, in a column on the right, each UAV's front
// camera of the same instant scaled into its tile, with a border in the vehicle's colour.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <map>
#include <memory>
#include <mutex>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "../sim/sim_fixture.hpp"
#include "app/camera_owners.hpp"
#include "objects/world_objects.hpp"
#include "physics/world.hpp"
#include "render/camera_setup.hpp"
#include "render/frame_service.hpp"
#include "render/overlay.hpp"
#include "render/video_recorder.hpp"
#include "sim/runner.hpp"
#include "sim/simulation.hpp"

namespace uavsim::server::render {
namespace {

constexpr double kRunS = 1.0;  // 15 fps: frames 0..14

TEST(TileLayout, ColumnOfTilesRightOfTheMainView) {
  // two 384 x 216 (16:9) cameras beside 640 x 480: tile height 480 / 2 = 240, width 240 * 16/9 =
  // 426.7, even: 426; the frame 640 + 426 = 1066 wide
  const TileLayout two = tile_layout(640, 480, {{384, 216}, {384, 216}});
  EXPECT_EQ(two.width_px, 1066);
  EXPECT_EQ(two.height_px, 480);
  ASSERT_EQ(two.tiles.size(), 2u);
  EXPECT_EQ(two.tiles[0].x_px, 640);
  EXPECT_EQ(two.tiles[0].y_px, 0);
  EXPECT_EQ(two.tiles[1].y_px, 240);
  EXPECT_EQ(two.tiles[1].width_px, 426);
  EXPECT_EQ(two.tiles[1].height_px, 240);
  // one 4:3 camera: still half the height (a lone tile is not the main view's size): 320 x 240
  const TileLayout one = tile_layout(640, 480, {{640, 480}});
  EXPECT_EQ(one.width_px, 960);
  EXPECT_EQ(one.tiles[0].width_px, 320);
  // four: 480 / 4 = 120 high, 160 wide
  const TileLayout four = tile_layout(640, 480, {{640, 480}, {640, 480}, {640, 480}, {640, 480}});
  EXPECT_EQ(four.width_px, 800);
  EXPECT_EQ(four.tiles[3].y_px, 360);
  // none: the main view alone
  EXPECT_EQ(tile_layout(640, 480, {}).width_px, 640);
}

// every frame of some cameras, in delivery order
class Collector : public FrameConsumer {
 public:
  explicit Collector(std::vector<int> cameras) : cameras_(std::move(cameras)) {}
  void want(int camera, int64_t, int64_t, std::vector<EncodingKey>* e, bool* must) override {
    if (std::find(cameras_.begin(), cameras_.end(), camera) == cameras_.end()) return;
    e->push_back({Encoding::kRgb, 0});
    *must = true;
  }
  void dropped(int, int64_t) override {}
  void deliver(const ReadyFrame& f) override {
    if (std::find(cameras_.begin(), cameras_.end(), f.camera) == cameras_.end()) return;
    std::lock_guard<std::mutex> lock(mutex_);
    frames[f.camera].push_back({f.stamp_us, *f.image({Encoding::kRgb, 0})});
  }
  std::mutex mutex_;
  std::map<int, std::vector<std::pair<int64_t, std::string>>> frames;

 private:
  std::vector<int> cameras_;
};

TEST(TiledRecord, TilesHoldTheOnboardCamerasOfTheSameInstant) {
  const auto world = sim::testing::make_sim("mbzirc2020.xml");
  sim::Simulation& s = *world;
  objects::ObjectSet objects = objects::add_world_objects(s);
  const CameraOwners owners = app::camera_owners(s.world(), objects);
  std::vector<std::string> overrides{"*:fps=15", "uav0_front:width=384,height=216",
                                     "uav1_front:width=384,height=216"};
  const std::vector<CameraSetup> cameras =
      discover_cameras(s.world().model(), owners, overrides, 1.0 / s.control_dt_s());
  int overview = -1, front0 = -1, front1 = -1;
  for (size_t i = 0; i < cameras.size(); ++i) {
    const std::string& n = cameras[i].config.camera;
    if (n == "overview") overview = static_cast<int>(i);
    if (n == "uav0_front") front0 = static_cast<int>(i);
    if (n == "uav1_front") front1 = static_cast<int>(i);
  }
  ASSERT_GE(overview, 0);
  ASSERT_GE(front0, 0);
  ASSERT_GE(front1, 0);

  Collector raw({overview, front0, front1});  // both outlive the frame service
  std::mutex composed_mutex;
  std::vector<std::string> composed;
  int width = 0, height = 0;
  std::unique_ptr<VideoRecorder> recorder;
  {
    FrameService frames(s.world().model(), cameras);
    RecorderOptions ro;
    ro.lossless = true;
    ro.tiles = {front0, front1};
    ro.sink = [&](const std::string& rgb, int w, int h) {
      std::lock_guard<std::mutex> lock(composed_mutex);
      composed.push_back(rgb);
      width = w;
      height = h;
    };
    recorder = std::make_unique<VideoRecorder>(frames, overview, "", std::move(ro));
    EXPECT_EQ(recorder->encoder(), "sink");
    frames.add_consumer(&raw);
    frames.add_consumer(recorder.get());
    sim::Runner runner(s, 0.0);
    runner.add_gate(sim::Phase::kCapture, "frames",
                    [&](double) { frames.capture(s.world().data()); });
    runner.run_until(kRunS);
    frames.wait_delivered();
  }
  recorder->finish();

  const TileLayout layout = tile_layout(640, 480, {{384, 216}, {384, 216}});
  ASSERT_EQ(raw.frames[overview].size(), 15u);  // t = 0, 1/15, ..., 14/15 s
  ASSERT_EQ(composed.size(), 15u);
  EXPECT_EQ(width, layout.width_px);
  EXPECT_EQ(height, layout.height_px);
  const auto at = [&](const std::string& img, int w, int x, int y) {
    const size_t i = (static_cast<size_t>(y) * w + x) * 3;
    return cv::Vec3b(img[i], img[i + 1], img[i + 2]);
  };
  constexpr int kLabelRowsPx = 24;  // the label's band at the tile's top
  constexpr int kBorderPx = 3;
  for (size_t k = 0; k < composed.size(); ++k) {
    const std::string& out = composed[k];
    // the main view, pixel for pixel (no overlay here)
    const std::string& main = raw.frames[overview][k].second;
    int main_diff = 0;
    for (int y = 0; y < 480; y += 3) {
      for (int x = 0; x < 640; x += 3) main_diff += at(out, width, x, y) != at(main, 640, x, y);
    }
    EXPECT_EQ(main_diff, 0) << "frame " << k;
    // each tile: its camera's frame of the same instant, scaled as the recorder scales it
    for (int t = 0; t < 2; ++t) {
      const int cam = t == 0 ? front0 : front1;
      ASSERT_EQ(raw.frames[cam].size(), composed.size());
      ASSERT_EQ(raw.frames[cam][k].first, raw.frames[overview][k].first);
      const PixelRect r = layout.tiles[static_cast<size_t>(t)];
      const cv::Mat src(216, 384, CV_8UC3, raw.frames[cam][k].second.data());
      cv::Mat scaled;
      cv::resize(src, scaled, cv::Size(r.width_px, r.height_px), 0, 0, cv::INTER_AREA);
      int diff = 0, n = 0;
      for (int y = kLabelRowsPx; y < r.height_px - kBorderPx; y += 2) {
        for (int x = kBorderPx; x < r.width_px - kBorderPx; x += 2, ++n) {
          diff += at(out, width, r.x_px + x, r.y_px + y) != scaled.at<cv::Vec3b>(y, x);
        }
      }
      EXPECT_EQ(diff, 0) << "frame " << k << " tile " << t << " of " << n << " pixels";
      // the border in the vehicle's colour (uav0 yellow, uav1 cyan), mid-height on the left edge
      uint8_t c[3];
      vehicle_colour_rgb(t, c);
      EXPECT_EQ(at(out, width, r.x_px, r.y_px + r.height_px / 2), cv::Vec3b(c[0], c[1], c[2]))
          << "frame " << k << " tile " << t;
    }
  }
  // the two onboard views differ (the quads stand 20 m apart: two cameras, not one copied twice)
  const PixelRect a = layout.tiles[0], b = layout.tiles[1];
  int differ = 0;
  for (int y = kLabelRowsPx; y < a.height_px - kBorderPx; ++y) {
    for (int x = kBorderPx; x < a.width_px - kBorderPx; ++x) {
      differ += at(composed.back(), width, a.x_px + x, a.y_px + y) !=
                at(composed.back(), width, b.x_px + x, b.y_px + y);
    }
  }
  EXPECT_GT(differ, 0);
  if (const char* dump = std::getenv("UAVSIM_TILED_PNG")) {
    cv::Mat rgb(height, width, CV_8UC3, composed.back().data()), bgr;
    cv::cvtColor(rgb, bgr, cv::COLOR_RGB2BGR);
    cv::imwrite(dump, bgr);
  }
}

}  // namespace
}  // namespace uavsim::server::render
