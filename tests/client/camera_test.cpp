// CameraSubscriber against uavsim-server (a subprocess: its frame service renders offscreen) on a
// small camera: frames as cv::Mat with stamps, intrinsics and pose, under lockstep and on the host
// clock.
#include "uavsim/client/camera.hpp"

#include <gtest/gtest.h>

#include <Eigen/LU>
#include <cmath>
#include <cstdio>
#include <regex>

#include "server_process.hpp"
#include "uavsim/client/event_loop.hpp"

namespace uavsim::client::testing {
namespace {

constexpr double kStampTol_s = 1e-6;  // frame stamps are sim times of whole control steps
constexpr double kIntrinsicsTol_px = 1e-6;
constexpr double kRotationTol = 1e-6;  // a rotation matrix's determinant

// the empty world, its cameras as each test asks
const std::string kEmptyWorld = std::string(UAVSIM_MODELS_DIR) + "/worlds/empty.xml";

const std::vector<std::string> kSmallCamera{"--camera", "overview:width=64,height=48,fps=10"};

TEST(CameraSubscriber, LockstepFramesArriveBeforeTheirTickWithIntrinsicsAndPose) {
  ServerProcess server(kEmptyWorld, kSmallCamera);
  ASSERT_GT(server.api_port(), 0) << server.output();
  auto l = EventLoop::create(LoopConfig::lockstep("127.0.0.1", server.api_port(), 0.02));
  ASSERT_TRUE(l) << l.message();
  EventLoop& loop = **l;
  std::vector<CameraFrame> frames;
  bool late = false;
  CameraConfig overview;
  overview.camera = "overview";
  auto sub = CameraSubscriber::subscribe(loop, overview, [&](const CameraFrame& f) {
    late = late || f.stamp_s > loop.now() + 0.02 + 1e-9;  // never later than the tick being handled
    frames.push_back(f);
  });
  ASSERT_TRUE(sub) << sub.message();
  EXPECT_EQ((*sub)->width(), 64);
  EXPECT_EQ((*sub)->height(), 48);
  EXPECT_DOUBLE_EQ((*sub)->fps(), 10.0);
  const double t0 = loop.now();
  ASSERT_TRUE(loop.run_for(1.0));
  ASSERT_GE(frames.size(), 9u);
  EXPECT_LE(frames.size(), 11u);
  EXPECT_FALSE(late);
  for (std::size_t i = 0; i < frames.size(); ++i) {
    const CameraFrame& f = frames[i];
    EXPECT_EQ(f.seq, static_cast<std::int64_t>(i));
    EXPECT_EQ(f.dropped, 0);
    EXPECT_GE(f.stamp_s, t0 - 1e-9);
    if (i > 0) {
      EXPECT_NEAR(f.stamp_s - frames[i - 1].stamp_s, 0.1, kStampTol_s);
    }
    ASSERT_EQ(f.image.rows, 48);
    ASSERT_EQ(f.image.cols, 64);
    EXPECT_EQ(f.image.type(), CV_8UC3);
  }
  const CameraFrame& f = frames.back();
  EXPECT_TRUE(f.vehicle.empty());
  EXPECT_NEAR(f.intrinsics.cx, 31.5, kIntrinsicsTol_px);
  EXPECT_NEAR(f.intrinsics.cy, 23.5, kIntrinsicsTol_px);
  EXPECT_GT(f.intrinsics.fx, 0.0);
  EXPECT_LT((f.pose.position_enu_m - Eigen::Vector3d(-12, -12, 8)).norm(), 1e-6);
  EXPECT_NEAR(f.pose.R_enu_cam.determinant(), 1.0, kRotationTol);
  cv::Scalar mean, stddev;
  cv::meanStdDev(f.image, mean, stddev);
  EXPECT_GT(stddev[0] + stddev[1] + stddev[2], 1.0) << "a blank image";
  // an unknown camera is refused with the simulator's message
  CameraConfig missing;
  missing.camera = "no_such_camera";
  auto bad = CameraSubscriber::subscribe(loop, missing, nullptr);
  ASSERT_FALSE(bad);
  EXPECT_EQ(bad.code(), Error::kDenied);
  EXPECT_NE(bad.message().find("overview"), std::string::npos) << bad.message();
}

TEST(CameraSubscriber, HostClockOwnConnectionGreyAndJpeg) {
  ServerProcess server(kEmptyWorld, kSmallCamera);
  ASSERT_GT(server.api_port(), 0) << server.output();
  auto l = EventLoop::create(LoopConfig::host());
  ASSERT_TRUE(l);
  EventLoop& loop = **l;
  const std::string api = "127.0.0.1:" + std::to_string(server.api_port());
  std::vector<CameraFrame> grey, jpeg;
  CameraConfig gc;
  gc.camera = "overview";
  gc.format = CameraFormat::kGrey;
  gc.api_address = api;
  auto g = CameraSubscriber::subscribe(loop, gc, [&](const CameraFrame& f) { grey.push_back(f); });
  ASSERT_TRUE(g) << g.message();
  CameraConfig jc = gc;
  jc.format = CameraFormat::kJpeg;
  jc.fps = 5;
  auto j = CameraSubscriber::subscribe(loop, jc, [&](const CameraFrame& f) { jpeg.push_back(f); });
  ASSERT_TRUE(j) << j.message();
  auto r = loop.run_until([&] { return grey.size() >= 3 && jpeg.size() >= 2; }, 30.0, "frames");
  ASSERT_TRUE(r) << r.message();
  EXPECT_EQ(grey[0].image.type(), CV_8UC1);
  EXPECT_EQ(grey[0].image.cols, 64);
  EXPECT_EQ(jpeg[0].image.type(), CV_8UC3);
  EXPECT_EQ(jpeg[0].image.rows, 48);
  EXPECT_NEAR(jpeg[1].stamp_s - jpeg[0].stamp_s, 0.2 * (jpeg[1].seq - jpeg[0].seq), kStampTol_s);
}

// depth and segmentation beside colour, typed: one frame per capture with all three images
TEST(CameraSubscriber, DepthAndSegmentationArriveTypedWithTheColourOfTheirCapture) {
  ServerProcess server(
      kEmptyWorld,
      {"--camera", "overview:width=160,height=120,fps=10,modalities=rgb+depth+segmentation"});
  ASSERT_GT(server.api_port(), 0) << server.output();
  auto l = EventLoop::create(LoopConfig::lockstep("127.0.0.1", server.api_port(), 0.02));
  ASSERT_TRUE(l) << l.message();
  EventLoop& loop = **l;
  std::vector<CameraFrame> frames;
  CameraConfig config;
  config.camera = "overview";
  config.depth = true;
  config.segmentation = true;
  auto sub =
      CameraSubscriber::subscribe(loop, config, [&](const CameraFrame& f) { frames.push_back(f); });
  ASSERT_TRUE(sub) << sub.message();
  EXPECT_GT((*sub)->depth_far_m(), (*sub)->depth_near_m());
  const std::vector<std::string>& classes = (*sub)->segmentation_classes();
  const std::vector<SegmentationObject>& objects = (*sub)->segmentation_objects();
  ASSERT_GT(classes.size(), 2u);
  EXPECT_EQ(classes[0], "none");
  ASSERT_TRUE(loop.run_for(0.5));
  ASSERT_GE(frames.size(), 4u);
  for (std::size_t i = 0; i < frames.size(); ++i)
    EXPECT_EQ(frames[i].seq, static_cast<std::int64_t>(i));
  const CameraFrame& f = frames.back();
  ASSERT_EQ(f.image.type(), CV_8UC3);
  ASSERT_EQ(f.depth_m.type(), CV_32FC1);
  ASSERT_EQ(f.object_ids.type(), CV_16UC1);
  ASSERT_EQ(f.class_ids.type(), CV_16UC1);
  ASSERT_EQ(f.depth_m.size(), f.image.size());
  // the bottom row sees the ground: its depth along the axis is the camera height over the ray's
  // slope, and its label is the ground's
  const float z = f.depth_m.at<float>(119, 80);
  EXPECT_TRUE(std::isfinite(z) && z > 1.0f && z < 30.0f) << z;
  const int object = f.object_ids.at<uint16_t>(119, 80);
  ASSERT_LT(static_cast<std::size_t>(object), objects.size());
  EXPECT_EQ(objects[static_cast<std::size_t>(object)].name, "ground");
  EXPECT_EQ(classes.at(static_cast<std::size_t>(f.class_ids.at<uint16_t>(119, 80))), "ground");
  // the quad at the origin is labelled a vehicle somewhere in the image
  bool vehicle = false;
  for (int v = 0; v < 120; ++v) {
    for (int u = 0; u < 160; ++u)
      vehicle = vehicle || classes.at(f.class_ids.at<uint16_t>(v, u)) == "vehicle";
  }
  EXPECT_TRUE(vehicle);

  // depth alone: no colour image; a camera without it refuses
  CameraConfig depth_only = config;
  depth_only.colour = false;
  depth_only.segmentation = false;
  (*sub).reset();
  frames.clear();
  auto d = CameraSubscriber::subscribe(loop, depth_only,
                                       [&](const CameraFrame& fr) { frames.push_back(fr); });
  ASSERT_TRUE(d) << d.message();
  ASSERT_TRUE(loop.run_for(0.3));
  ASSERT_FALSE(frames.empty());
  EXPECT_TRUE(frames.back().image.empty());
  EXPECT_FALSE(frames.back().depth_m.empty());
  EXPECT_TRUE(frames.back().object_ids.empty());
  CameraConfig none = config;
  none.colour = false;
  none.depth = false;
  none.segmentation = false;
  auto bad = CameraSubscriber::subscribe(loop, none, nullptr);
  ASSERT_FALSE(bad);
  EXPECT_EQ(bad.code(), Error::kInvalidArgument);
}

// the README's example program, unchanged, against a server: UAVSIM_MAVLINK + UAVSIM_LOCKSTEP
TEST(Examples, FlySquareUnderLockstep) {
  ServerProcess server(kEmptyWorld, {"--no-cameras"});
  ASSERT_GT(server.mavlink_port(), 0) << server.output();
  const std::string cmd = "UAVSIM_MAVLINK=tcp:127.0.0.1:" + std::to_string(server.mavlink_port()) +
                          " UAVSIM_LOCKSTEP=127.0.0.1:" + std::to_string(server.api_port()) +
                          " timeout 120 " + FLY_SQUARE + " 2>&1";
  FILE* p = popen(cmd.c_str(), "r");
  ASSERT_NE(p, nullptr);
  std::string out;
  char buf[512];
  while (fgets(buf, sizeof(buf), p) != nullptr) out += buf;
  const int status = pclose(p);
  EXPECT_EQ(status, 0) << out;
  EXPECT_NE(out.find("corner (0, 0) reached"), std::string::npos) << out;
  EXPECT_NE(out.find("landed"), std::string::npos) << out;
}

}  // namespace
}  // namespace uavsim::client::testing
