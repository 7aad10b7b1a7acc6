// Depth and segmentation beside colour (docs/protocol.md "Camera frames"), on a scene with the
// truck and its marker, a balloon, a quad and the ground (tests/data/worlds/camera_scene.xml):
//   - depth against physics: at sample pixels the depth equals the distance along the optical axis
//   to what
//     mj_ray hits through that pixel, and pixels whose ray hits nothing are invalid (NaN)
//   - segmentation against geometry: the balloon's pixels are where its sphere projects, the marker
//   class
//     covers the marker's projected square, no object out of view is labelled; ids are stable
//     across frames and runs
//   - depth field conditions: seeded, the stated statistics, never on segmentation
#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <memory>
#include <opencv2/imgproc.hpp>
#include <set>
#include <string>
#include <vector>

#include "physics/world.hpp"
#include "render/camera_setup.hpp"
#include "render/frame_service.hpp"
#include "render/video_recorder.hpp"
#include "uavsim/common/angles.hpp"

namespace uavsim::server::render {
namespace {

const std::string kScene = std::string(UAVSIM_TEST_DATA_DIR) + "/worlds/camera_scene.xml";
constexpr double kControlHz = 100.0;
// depth tolerance: 2 cm for the tessellation of round geoms (MuJoCo's spheres and cylinders are
// polygons: a 0.35 m wheel's sagitta is under 3 mm) and the 24-bit depth buffer, plus 0.2 % of the
// depth
constexpr double kDepthTolM = 0.02;
constexpr double kDepthTolRel = 0.002;
const Eigen::Vector3d kBalloonCentre(4.0, -12.0, 2.7);  // b0 at (4, -12, 0), its sphere 2.7 m up
constexpr double kBalloonRadiusM = 0.3;
constexpr double kCentroidTol_px = 0.5;
constexpr double kRadiusRelTol = 0.08;
constexpr double kAreaRelTol = 0.08;
// 200000 samples of the depth noise (sd 0.2 m at 10 m) and of the 3 % dropout
constexpr double kNoiseMeanTol_m = 0.005;
constexpr double kNoiseSdTol_m = 0.01;
constexpr double kDropoutTol = 0.003;

// one capture of a camera: every image and its pose
struct Capture {
  int64_t stamp_us = 0;
  int width = 0, height = 0;
  Eigen::Vector3d position_enu_m;
  Eigen::Matrix3d R_enu_cam;
  double fx = 0, fy = 0, cx = 0, cy = 0;
  std::string rgb;
  std::vector<float> depth_m;
  std::vector<uint16_t> object, cls;
};

// wants colour, depth and segmentation of every frame; never drops one
class Taker : public FrameConsumer {
 public:
  void want(int, int64_t, int64_t, std::vector<EncodingKey>* e, bool* must) override {
    e->push_back({Encoding::kRgb, 0});
    e->push_back({Encoding::kDepth, 0});
    e->push_back({Encoding::kSegmentation, 0});
    *must = true;
  }
  void dropped(int, int64_t) override { ++dropped_; }
  void deliver(const ReadyFrame& f) override {
    Capture c;
    c.stamp_us = f.stamp_us;
    c.width = f.info->width_px;
    c.height = f.info->height_px;
    c.position_enu_m = f.position_enu_m;
    c.R_enu_cam = f.R_enu_cam;
    c.fx = f.info->fx_px;
    c.fy = f.info->fy_px;
    c.cx = f.info->cx_px;
    c.cy = f.info->cy_px;
    c.rgb = *f.image({Encoding::kRgb, 0});
    const std::string& depth = *f.image({Encoding::kDepth, 0});
    c.depth_m.resize(depth.size() / 4);
    std::memcpy(c.depth_m.data(), depth.data(), depth.size());
    const std::string& seg = *f.image({Encoding::kSegmentation, 0});
    for (size_t i = 0; i + 3 < seg.size(); i += 4) {
      c.object.push_back(static_cast<uint16_t>(static_cast<uint8_t>(seg[i]) |
                                               static_cast<uint8_t>(seg[i + 1]) << 8));
      c.cls.push_back(static_cast<uint16_t>(static_cast<uint8_t>(seg[i + 2]) |
                                            static_cast<uint8_t>(seg[i + 3]) << 8));
    }
    captures_[f.info->name].push_back(std::move(c));
  }
  std::map<std::string, std::vector<Capture>>
      captures_;  // render thread; read after wait_delivered
  int dropped_ = 0;
};

// the scene, loaded and forwarded, with its frame service (no objects run: the truck and the
// balloon stay where the world puts them)
struct Scene {
  std::unique_ptr<physics::World> world;
  std::vector<CameraSetup> cameras;
  std::unique_ptr<FrameService> frames;
  Taker taker;

  explicit Scene(const std::vector<std::string>& overrides = {}) {
    physics::ComposeOptions co;
    co.models_dir = UAVSIM_MODELS_DIR;
    world = physics::World::load(kScene, co);
    mj_forward(world->model(), world->data());
    CameraOwners owners;
    for (const auto& v : world->vehicles())
      owners.vehicle_root_bodies.emplace_back(v.body_id, v.name);
    cameras = discover_cameras(world->model(), owners, overrides, kControlHz);
    FrameServiceOptions fo;
    fo.owners = owners;
    frames = std::make_unique<FrameService>(world->model(), cameras, fo);
    frames->add_consumer(&taker);
  }
  // frames of every camera at sim time t (the state is the world's as it stands)
  void capture_at(double t) {
    world->data()->time = t;
    frames->capture(world->data());
    frames->wait_delivered();
  }
  const Capture& last(const std::string& camera) { return taker.captures_.at(camera).back(); }
  uint16_t object_id(const std::string& name) const {
    for (const SegmentObject& o : frames->labels().objects) {
      if (o.name == name) return o.id;
    }
    ADD_FAILURE() << "no object " << name;
    return 0;
  }
};

// the pixel a point projects to, and its depth along the optical axis
Eigen::Vector3d project(const Capture& c, const Eigen::Vector3d& p_enu) {
  const Eigen::Vector3d p = c.R_enu_cam.transpose() * (p_enu - c.position_enu_m);
  return {c.fx * p.x() / p.z() + c.cx, c.fy * p.y() / p.z() + c.cy, p.z()};
}

// whether the 3 x 3 pixels around (u, v) show one object (not an edge, where a ray and a raster
// sample differ)
bool interior(const Capture& c, int u, int v) {
  const uint16_t id = c.object[static_cast<size_t>(v) * c.width + u];
  for (int dv = -1; dv <= 1; ++dv) {
    for (int du = -1; du <= 1; ++du) {
      if (c.object[static_cast<size_t>(v + dv) * c.width + (u + du)] != id) return false;
    }
  }
  return true;
}

TEST(CameraDepth, MatchesTheRayCastThroughSamplePixels) {
  Scene scene;
  scene.capture_at(0.0);
  const mjModel* m = scene.world->model();
  const mjData* d = scene.world->data();
  const SegmentationLabels& labels = scene.frames->labels();
  for (const char* name : {"rgbd", "above"}) {
    const Capture& c = scene.last(name);
    ASSERT_EQ(c.depth_m.size(), static_cast<size_t>(c.width * c.height));
    std::set<SegmentClass> hit;
    int checked = 0, empty = 0;
    for (int v = 4; v < c.height - 4; v += 6) {
      for (int u = 4; u < c.width - 4; u += 6) {
        // the ray through the pixel's centre, from the optical centre
        const Eigen::Vector3d dir_cam((u - c.cx) / c.fx, (v - c.cy) / c.fy, 1.0);
        const Eigen::Vector3d dir_enu = (c.R_enu_cam * dir_cam).normalized();
        int geom = -1;
        const double r =
            mj_ray(m, d, c.position_enu_m.data(), dir_enu.data(), nullptr, 1, -1, &geom);
        const float z = c.depth_m[static_cast<size_t>(v) * c.width + u];
        if (!interior(c, u, v)) continue;
        if (r < 0) {
          EXPECT_TRUE(std::isnan(z))
              << name << " (" << u << ", " << v << ") sees nothing, depth " << z;
          ++empty;
          continue;
        }
        // distance along the ray => along the optical axis
        const double expected = r / dir_cam.norm();
        ASSERT_FALSE(std::isnan(z)) << name << " (" << u << ", " << v << ") ray hits at " << r;
        EXPECT_NEAR(z, expected, kDepthTolM + kDepthTolRel * expected)
            << name << " (" << u << ", " << v << ")";
        // and the segmentation labels what the ray hit
        EXPECT_EQ(c.object[static_cast<size_t>(v) * c.width + u],
                  labels.geom_object.at(static_cast<size_t>(geom)))
            << name << " (" << u << ", " << v << ") geom " << mj_id2name(m, mjOBJ_GEOM, geom);
        hit.insert(labels.geom_class.at(static_cast<size_t>(geom)));
        ++checked;
      }
    }
    EXPECT_GT(checked, 500) << name;
    EXPECT_TRUE(hit.count(SegmentClass::kGround) && hit.count(SegmentClass::kTruck)) << name;
    if (std::string(name) == "rgbd") {
      // the oblique camera sees the balloon and above the horizon
      EXPECT_TRUE(hit.count(SegmentClass::kBalloon)) << "no sample pixel on the balloon";
      EXPECT_GT(empty, 100) << "the sky is not empty";
    }
  }
}

TEST(CameraSegmentation, BalloonPixelsAreWhereTheBalloonProjects) {
  Scene scene;
  scene.capture_at(0.0);
  const Capture& c = scene.last("rgbd");
  const uint16_t balloon = scene.object_id("b0");
  double su = 0, sv = 0;
  int n = 0;
  for (int v = 0; v < c.height; ++v) {
    for (int u = 0; u < c.width; ++u) {
      const size_t i = static_cast<size_t>(v) * c.width + u;
      if (c.object[i] != balloon) continue;
      EXPECT_EQ(c.cls[i], static_cast<uint16_t>(SegmentClass::kBalloon));
      su += u;
      sv += v;
      ++n;
    }
  }
  const Eigen::Vector3d p = project(c, kBalloonCentre);
  // a sphere at distance D seen at angle theta off the optical axis projects to an ellipse: its
  // angular radius a = asin(r / D) spans f tan(a) / cos(theta) across and f tan(a) / cos^2(theta)
  // radially, so the radius of the disc of equal area is f tan(a) / cos^1.5(theta), tan(a) = r /
  // sqrt(D^2 - r^2)
  const Eigen::Vector3d p_cam = c.R_enu_cam.transpose() * (kBalloonCentre - c.position_enu_m);
  const double dist = p_cam.norm();
  const double cos_theta = p_cam.z() / dist;
  const double radius_px = c.fx * kBalloonRadiusM /
                           std::sqrt(dist * dist - kBalloonRadiusM * kBalloonRadiusM) /
                           std::pow(cos_theta, 1.5);
  ASSERT_GT(n, 20);
  EXPECT_NEAR(su / n, p.x(), kCentroidTol_px);
  EXPECT_NEAR(sv / n, p.y(), kCentroidTol_px);
  EXPECT_NEAR(std::sqrt(n / common::kPi), radius_px, kRadiusRelTol * radius_px);
}

TEST(CameraSegmentation, MarkerClassCoversTheMarkerAndNothingOutOfViewIsLabelled) {
  Scene scene;
  scene.capture_at(0.0);
  const Capture& c = scene.last("above");
  // the marker: 1.5 m square, its top 1.501 m up, centred on the origin; straight below the camera
  // its projection is a square (image x east, y south)
  const Eigen::Vector3d lo = project(c, {-0.75, 0.75, 1.501});
  const Eigen::Vector3d hi = project(c, {0.75, -0.75, 1.501});
  int inside = 0, marker = 0;
  for (int v = 0; v < c.height; ++v) {
    for (int u = 0; u < c.width; ++u) {
      const size_t i = static_cast<size_t>(v) * c.width + u;
      const bool is_marker = c.cls[i] == static_cast<uint16_t>(SegmentClass::kMarker);
      marker += is_marker;
      // pixels one pixel or more inside the square are all marker
      if (u > lo.x() + 1 && u < hi.x() - 1 && v > lo.y() + 1 && v < hi.y() - 1) {
        ++inside;
        EXPECT_TRUE(is_marker) << "(" << u << ", " << v << ")";
      }
    }
  }
  const double area = (hi.x() - lo.x()) * (hi.y() - lo.y());
  ASSERT_GT(inside, 100);
  EXPECT_NEAR(marker, area,
              kAreaRelTol * area);  // edge pixels: half the perimeter's pixels either way at most

  // the camera above sees the ground, the truck and its marker, not the balloon, its pole or the
  // quad
  std::set<uint16_t> seen(c.object.begin(), c.object.end());
  EXPECT_EQ(seen, (std::set<uint16_t>{scene.object_id("ground"), scene.object_id("truck"),
                                      scene.object_id("truck/marker")}));
  // the oblique one sees them all
  const Capture& o = scene.last("rgbd");
  std::set<uint16_t> all(o.object.begin(), o.object.end());
  for (const char* name : {"ground", "truck", "truck/marker", "b0", "b0/pole", "uav0"}) {
    EXPECT_TRUE(all.count(scene.object_id(name))) << name;
  }
  EXPECT_TRUE(all.count(0)) << "the sky is labelled";
}

TEST(CameraSegmentation, IdsAreStableAcrossFramesAndRuns) {
  std::vector<std::string> first_run;
  std::vector<SegmentObject> first_labels;
  for (int run = 0; run < 2; ++run) {
    Scene scene;
    scene.capture_at(0.0);
    scene.capture_at(0.1);
    const auto& frames = scene.taker.captures_.at("rgbd");
    ASSERT_EQ(frames.size(), 2u);
    EXPECT_EQ(frames[0].object, frames[1].object);
    EXPECT_EQ(frames[0].cls, frames[1].cls);
    std::vector<std::string> names;
    for (const SegmentObject& o : scene.frames->labels().objects) names.push_back(o.name);
    if (run == 0) {
      first_run = names;
      first_labels = scene.frames->labels().objects;
      continue;
    }
    EXPECT_EQ(names, first_run);
    for (size_t i = 0; i < first_labels.size(); ++i) {
      EXPECT_EQ(scene.frames->labels().objects[i].id, first_labels[i].id);
      EXPECT_EQ(scene.frames->labels().objects[i].cls, first_labels[i].cls);
    }
  }
  // the table starts with "none" and names every object of the scene once
  ASSERT_FALSE(first_run.empty());
  EXPECT_EQ(first_run[0], "none");
  EXPECT_EQ(std::set<std::string>(first_run.begin(), first_run.end()).size(), first_run.size());
}

// field conditions on depth: seeded, the stated statistics; segmentation stays exact
TEST(CameraDepth, FieldConditionsAreSeededAndNeverTouchSegmentation) {
  FrameCamera cam;
  cam.depth_near_m = 0.1;
  cam.depth_noise_m = 0.002;
  cam.depth_dropout = 0.03;
  cam.depth_max_m = 40.0;
  constexpr size_t kPixels = 200000;
  std::vector<float> at10(kPixels, 10.0f);
  std::vector<float> again = at10;
  apply_depth_effects(cam, 7, 0, 3, &at10);
  apply_depth_effects(cam, 7, 0, 3, &again);
  ASSERT_EQ(std::memcmp(at10.data(), again.data(), kPixels * sizeof(float)), 0) << "not seeded";
  std::vector<float> other(kPixels, 10.0f);
  apply_depth_effects(cam, 7, 0, 4, &other);
  EXPECT_NE(std::memcmp(at10.data(), other.data(), kPixels * sizeof(float)), 0)
      << "same noise in two frames";
  // sd(10 m) = 0.002 * 10^2 = 0.2 m; 3 % dropped
  double sum = 0, sum2 = 0;
  int valid = 0;
  for (float z : at10) {
    if (std::isnan(z)) continue;
    sum += z;
    sum2 += static_cast<double>(z) * z;
    ++valid;
  }
  const double mean = sum / valid;
  EXPECT_NEAR(mean, 10.0, kNoiseMeanTol_m);
  EXPECT_NEAR(std::sqrt(sum2 / valid - mean * mean), 0.2, kNoiseSdTol_m);
  EXPECT_NEAR(1.0 - static_cast<double>(valid) / kPixels, 0.03, kDropoutTol);
  // beyond the range: nothing measured
  std::vector<float> far(100, 41.0f);
  apply_depth_effects(cam, 7, 0, 3, &far);
  for (float z : far) EXPECT_TRUE(std::isnan(z));

  // the scene with --realism field's camera settings: depth differs, segmentation is the same
  Scene ideal;
  Scene field({"*:noise=3,brightness=0.08,depth_noise=0.002,depth_dropout=0.03,depth_max_m=40"});
  ideal.capture_at(0.0);
  field.capture_at(0.0);
  EXPECT_EQ(ideal.last("rgbd").object, field.last("rgbd").object);
  EXPECT_EQ(ideal.last("rgbd").cls, field.last("rgbd").cls);
  EXPECT_NE(std::memcmp(ideal.last("rgbd").depth_m.data(), field.last("rgbd").depth_m.data(),
                        ideal.last("rgbd").depth_m.size() * sizeof(float)),
            0);
}

TEST(FalseColour, DepthNearRedFarBlueInvalidBlackAndSegmentationByClass) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const std::vector<float> depth{1.0f, 100.0f, nan};
  uint8_t rgb[9];
  false_colour_depth(depth.data(), 3, 1, 1.0, 100.0, rgb);
  EXPECT_GT(rgb[0], rgb[2]) << "near is red";
  EXPECT_GT(rgb[5], rgb[3]) << "far is blue";
  EXPECT_EQ(rgb[6] + rgb[7] + rgb[8], 0) << "nothing measured is black";
  // object 5 of class balloon, object 9 of class truck, nothing
  const uint8_t seg[12] = {5, 0, 3, 0, 9, 0, 5, 0, 0, 0, 0, 0};
  false_colour_segmentation(seg, 3, 1, rgb);
  EXPECT_GT(rgb[1], rgb[0] + 50) << "balloon green";
  EXPECT_GT(rgb[5], rgb[3] + 50) << "truck blue";
  EXPECT_EQ(rgb[6] + rgb[7] + rgb[8], 0);
}

// --record-tile rgbd:depth --record-tile rgbd:segmentation: the recorder asks the camera for those
// images and tiles them in false colour beside the main view
TEST(FalseColour, RecorderTilesDepthAndSegmentation) {
  Scene scene;
  int plain = -1, rgbd = -1;
  for (size_t i = 0; i < scene.cameras.size(); ++i) {
    if (scene.cameras[i].config.camera == "plain") plain = static_cast<int>(i);
    if (scene.cameras[i].config.camera == "rgbd") rgbd = static_cast<int>(i);
  }
  std::vector<std::string> composed;
  int width = 0;
  RecorderOptions ro;
  ro.lossless = true;
  ro.tiles = {rgbd, rgbd};
  ro.tile_modalities = {Encoding::kDepth, Encoding::kSegmentation};
  ro.sink = [&](const std::string& rgb, int w, int) {
    composed.push_back(rgb);
    width = w;
  };
  // a tile of what the camera does not give is refused
  int above = -1;
  for (size_t i = 0; i < scene.cameras.size(); ++i) {
    if (scene.cameras[i].config.camera == "above") above = static_cast<int>(i);
  }
  auto ignore = [](const std::string&, int, int) {};
  EXPECT_THROW(
      VideoRecorder(*scene.frames, above, "",
                    RecorderOptions{1, false, {plain}, ignore, {Encoding::kDepth}, nullptr}),
      std::invalid_argument);
  auto recorder = std::make_unique<VideoRecorder>(*scene.frames, plain, "", std::move(ro));
  scene.frames->add_consumer(recorder.get());
  scene.capture_at(0.0);
  scene.capture_at(0.1);  // a frame of another instant flushes the first
  recorder->finish();
  ASSERT_GE(composed.size(), 1u);
  const TileLayout layout = tile_layout(320, 240, {{320, 240}, {320, 240}});
  const std::string& out = composed.front();
  // each tile below its label band and inside its border: the camera's depth and segmentation of
  // the same instant in false colour, shrunk as the recorder shrinks them (nearest pixel); the
  // depth map's range: max(near plane, 1 m) to min(far plane, 100 m) for a camera without
  // depth_max_m
  const Capture& c = scene.taker.captures_.at("rgbd").front();
  const FrameCamera& cam = scene.frames->cameras()[static_cast<size_t>(rgbd)];
  cv::Mat depth_rgb(240, 320, CV_8UC3), seg_rgb(240, 320, CV_8UC3);
  false_colour_depth(c.depth_m.data(), 320, 240, std::max(cam.depth_near_m, 1.0),
                     std::min(cam.depth_far_m, 100.0), depth_rgb.data);
  std::vector<uint8_t> seg(c.object.size() * 4);
  for (size_t i = 0; i < c.object.size(); ++i) {
    seg[4 * i] = static_cast<uint8_t>(c.object[i] & 0xFF);
    seg[4 * i + 1] = static_cast<uint8_t>(c.object[i] >> 8);
    seg[4 * i + 2] = static_cast<uint8_t>(c.cls[i] & 0xFF);
    seg[4 * i + 3] = static_cast<uint8_t>(c.cls[i] >> 8);
  }
  false_colour_segmentation(seg.data(), 320, 240, seg_rgb.data);
  constexpr int kLabelRowsPx = 24, kBorderPx = 3;
  int checked = 0, green = 0;
  for (int t = 0; t < 2; ++t) {
    const PixelRect& r = layout.tiles[static_cast<size_t>(t)];
    cv::Mat expected;
    cv::resize(t == 0 ? depth_rgb : seg_rgb, expected, cv::Size(r.width_px, r.height_px), 0, 0,
               cv::INTER_NEAREST);
    int differ = 0;
    for (int y = kLabelRowsPx; y < r.height_px - kBorderPx; ++y) {
      for (int x = kBorderPx; x < r.width_px - kBorderPx; ++x) {
        const auto* p = reinterpret_cast<const uint8_t*>(out.data()) +
                        (static_cast<size_t>(r.y_px + y) * width + r.x_px + x) * 3;
        const auto* e = expected.ptr<uint8_t>(y) + 3 * x;
        differ += p[0] != e[0] || p[1] != e[1] || p[2] != e[2];
        green += t == 1 && p[1] > p[0] + 60 && p[1] > p[2] + 60;
        ++checked;
      }
    }
    EXPECT_EQ(differ, 0) << (t == 0 ? "depth" : "segmentation") << " tile";
  }
  EXPECT_GT(checked, 10000);
  EXPECT_GT(green, 0) << "no balloon in the segmentation tile";
}

TEST(CameraModalities, ConfigKeysAreRangeChecked) {
  CameraConfig c;
  apply_camera_options("modalities=depth+segmentation", "t", &c);
  EXPECT_FALSE(c.modalities.rgb);
  EXPECT_FALSE(c.modalities.grey);
  EXPECT_TRUE(c.modalities.depth);
  EXPECT_TRUE(c.modalities.segmentation);
  for (const char* bad :
       {"modalities=rgb+thermal", "modalities=", "modalities=rgb+rgb", "depth_noise=-1",
        "depth_noise=2", "depth_dropout=1.5", "depth_max_m=0", "depth_max_m=nan"}) {
    EXPECT_THROW(apply_camera_options(bad, "t", &c), std::invalid_argument) << bad;
  }
}

}  // namespace
}  // namespace uavsim::server::render
