// export_video_log on the depth and segmentation planes of a version 2 log: false-colour pictures
// mapped as documented (video_log.hpp), exact .npy dumps, and refusals before anything is written.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <limits>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>
#include <set>

#include "plane_log.hpp"
#include "uavsim/vision/video_log.hpp"

namespace uavsim::vision {
namespace {

namespace fs = std::filesystem;
using test::kPlaneHeightPx;
using test::kPlaneWidthPx;
using test::mat_bytes;
using test::plane_frame;
using test::read_npy;
using test::write_plane_log;

constexpr int kFrames = 4;

class VideoLogExportTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() /
           (std::string("uavsim_vlog_export_") + info->name() + "_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    ASSERT_TRUE(write_plane_log(dir_ / "planes.vlog", kFrames));
  }
  void TearDown() override { fs::remove_all(dir_); }
  // pictures of the plane alone: no drawings on top
  VideoLogExportOptions plain(VideoLogPlane plane) const {
    VideoLogExportOptions o;
    o.plane = plane;
    o.draw_overlays = false;
    o.draw_text = false;
    return o;
  }
  fs::path dir_;
};

// OpenCV's turbo map at one level: the documented colour of a depth
cv::Vec3b turbo(int level) {
  cv::Mat one(1, 1, CV_8UC1, cv::Scalar(level)), bgr;
  cv::applyColorMap(one, bgr, cv::COLORMAP_TURBO);
  return bgr.at<cv::Vec3b>(0, 0);
}

TEST_F(VideoLogExportTest, DepthBecomesLogScaledTurboPngsAndExactNpys) {
  VideoLogExportOptions o = plain(VideoLogPlane::kDepth);
  o.png_dir = dir_ / "png";
  o.raw_dir = dir_ / "raw";
  o.mp4_path = dir_ / "depth.mp4";
  auto exported = export_video_log(dir_ / "planes.vlog", o);
  ASSERT_TRUE(exported.ok()) << to_string(exported.error());
  EXPECT_EQ(exported.value(), static_cast<size_t>(kFrames));
  EXPECT_FALSE(fs::exists(dir_ / "png" / "frame_000004.png"));
  EXPECT_FALSE(fs::exists(dir_ / "raw" / "depth_000004.npy"));

  // the PNGs: defaults near 1 m, far 100 m; level = 255 (1 - log(z / 1) / log(100 / 1))
  const cv::Mat png = cv::imread((dir_ / "png" / "frame_000000.png").string());
  ASSERT_EQ(png.size(), cv::Size(kPlaneWidthPx, kPlaneHeightPx));
  EXPECT_EQ(png.at<cv::Vec3b>(0, 7), cv::Vec3b(0, 0, 0));  // row 0: NaN, nothing measured
  EXPECT_EQ(png.at<cv::Vec3b>(1, 0), turbo(255));          // z = 1 m: near
  EXPECT_EQ(png.at<cv::Vec3b>(5, 0), turbo(255));          // 0.5 m, nearer than near: near
  EXPECT_EQ(png.at<cv::Vec3b>(6, 39), turbo(0));           // 500 m, beyond far: far
  EXPECT_EQ(png.at<cv::Vec3b>(1, 9), turbo(128));  // z = 10 m: 255 (1 - 1/2) = 127.5, rounded 128
  EXPECT_EQ(png.at<cv::Vec3b>(2, 39), turbo(51));  // z = 40 m: 255 (1 - log 40 / log 100) = 51.0
  EXPECT_NE(turbo(255), turbo(0));
  // frame 3: 0.75 m deeper, z(x = 9) = 10.75 m: 255 (1 - log 10.75 / log 100) = 123.3 => 123
  const cv::Mat png3 = cv::imread((dir_ / "png" / "frame_000003.png").string());
  EXPECT_EQ(png3.at<cv::Vec3b>(1, 9), turbo(123));

  // another range moves the colours: near 10 m, far 40 m puts 10 m at red and 40 m at blue
  o = plain(VideoLogPlane::kDepth);
  o.png_dir = dir_ / "range";
  o.depth_near_m = 10.0;
  o.depth_far_m = 40.0;
  ASSERT_TRUE(export_video_log(dir_ / "planes.vlog", o).ok());
  const cv::Mat ranged = cv::imread((dir_ / "range" / "frame_000000.png").string());
  EXPECT_EQ(ranged.at<cv::Vec3b>(1, 9), turbo(255));
  EXPECT_EQ(ranged.at<cv::Vec3b>(1, 39), turbo(0));
  EXPECT_EQ(ranged.at<cv::Vec3b>(1, 19), turbo(128));  // 20 m: 255 (1 - log 2 / log 4) = 127.5

  // the raw dumps are the logged floats bit for bit (NaN included), as numpy reads them
  for (int i = 0; i < kFrames; ++i) {
    char name[32];
    std::snprintf(name, sizeof(name), "depth_%06d.npy", i);
    const test::Npy npy = read_npy(dir_ / "raw" / name);
    EXPECT_EQ(npy.descr, "<f4");
    EXPECT_EQ(npy.rows, kPlaneHeightPx);
    EXPECT_EQ(npy.cols, kPlaneWidthPx);
    EXPECT_EQ(npy.data, mat_bytes(plane_frame(i).depth_m)) << name;
  }

  // the MP4 holds every frame
  cv::VideoCapture mp4((dir_ / "depth.mp4").string());
  ASSERT_TRUE(mp4.isOpened());
  int frames = 0;
  for (cv::Mat f; mp4.read(f);) ++frames;
  EXPECT_EQ(frames, kFrames);
}

TEST_F(VideoLogExportTest, IdPlanesTakeOneColourPerIdInEveryFrame) {
  // the palette by its definition: id 1 at hue 137.508 deg (sextant 2: g = v, r = m, b = x + m),
  // v = 1, s = 0.85: c = 0.85, m = 0.15, x = c (1 - |137.508/60 - 2 - 1|) = 0.248;
  // BGR = 255 (0.398, 1, 0.15) = (101, 255, 38)
  EXPECT_EQ(id_colour_bgr(0), cv::Vec3b(0, 0, 0));
  EXPECT_EQ(id_colour_bgr(1), cv::Vec3b(101, 255, 38));
  std::set<std::tuple<int, int, int>> colours;
  for (int id = 1; id <= 255; ++id) {
    const cv::Vec3b c = id_colour_bgr(static_cast<uint16_t>(id));
    colours.insert({c[0], c[1], c[2]});
    EXPECT_NE(c, cv::Vec3b(0, 0, 0)) << id;
  }
  EXPECT_EQ(colours.size(), 255u);  // no two of the first 255 ids alike

  for (VideoLogPlane plane : {VideoLogPlane::kObjectIds, VideoLogPlane::kClassIds}) {
    VideoLogExportOptions o = plain(plane);
    o.png_dir = dir_ / to_string(plane);
    o.raw_dir = dir_ / (std::string(to_string(plane)) + "_raw");
    auto exported = export_video_log(dir_ / "planes.vlog", o);
    ASSERT_TRUE(exported.ok()) << to_string(exported.error());
    EXPECT_EQ(exported.value(), static_cast<size_t>(kFrames));
    for (int i : {0, kFrames - 1}) {
      char name[32];
      std::snprintf(name, sizeof(name), "frame_%06d.png", i);
      const cv::Mat png = cv::imread((o.png_dir / name).string());
      const VideoLogFrame f = plane_frame(i);
      const cv::Mat& ids = plane == VideoLogPlane::kObjectIds ? f.object_ids : f.class_ids;
      ASSERT_EQ(png.size(), ids.size());
      int mismatched = 0;
      for (int y = 0; y < ids.rows; ++y)
        for (int x = 0; x < ids.cols; ++x)
          mismatched += png.at<cv::Vec3b>(y, x) != id_colour_bgr(ids.at<uint16_t>(y, x));
      EXPECT_EQ(mismatched, 0) << to_string(plane) << " frame " << i;
      EXPECT_EQ(png.at<cv::Vec3b>(0, 0), cv::Vec3b(0, 0, 0));  // id 0: nothing hit
      std::snprintf(name, sizeof(name), "%s_%06d.npy", to_string(plane), i);
      const test::Npy npy = read_npy(o.raw_dir / name);
      EXPECT_EQ(npy.descr, "<u2");
      EXPECT_EQ(npy.rows, kPlaneHeightPx);
      EXPECT_EQ(npy.data, mat_bytes(ids)) << name;
    }
  }
}

TEST_F(VideoLogExportTest, OverlaysAndTextGoOnThePlanePicture) {
  VideoLogExportOptions o = plain(VideoLogPlane::kClassIds);
  o.draw_overlays = true;
  o.png_dir = dir_ / "circle";
  ASSERT_TRUE(export_video_log(dir_ / "planes.vlog", o).ok());
  // the logged circle (green, 3 px wide, radius 5 around (20, 15)) covers (25, 15)
  const cv::Mat circle = cv::imread((dir_ / "circle" / "frame_000000.png").string());
  EXPECT_EQ(circle.at<cv::Vec3b>(15, 25), cv::Vec3b(0, 255, 0));
  // the frame's text ("frame 0", white on black, top left) changes the top rows only
  o = plain(VideoLogPlane::kClassIds);
  o.draw_text = true;
  o.png_dir = dir_ / "text";
  ASSERT_TRUE(export_video_log(dir_ / "planes.vlog", o).ok());
  const cv::Mat text = cv::imread((dir_ / "text" / "frame_000000.png").string());
  const cv::Mat bare = false_colour_ids(plane_frame(0).class_ids);
  cv::Mat diff, differs;  // per row: the largest difference
  cv::absdiff(text, bare, diff);
  cv::reduce(diff.reshape(1, text.rows), differs, 1, cv::REDUCE_MAX);
  EXPECT_GT(differs.at<uint8_t>(10, 0), 0);
  EXPECT_EQ(cv::countNonZero(differs.rowRange(20, text.rows)), 0);
}

TEST_F(VideoLogExportTest, ALogWithoutThePlaneIsRefusedBeforeAnythingIsWritten) {
  ASSERT_TRUE(write_plane_log(dir_ / "colour.vlog", 2, false));
  for (VideoLogPlane plane :
       {VideoLogPlane::kDepth, VideoLogPlane::kObjectIds, VideoLogPlane::kClassIds}) {
    VideoLogExportOptions o = plain(plane);
    o.png_dir = dir_ / "out";
    o.raw_dir = dir_ / "raw";
    o.mp4_path = dir_ / "out.mp4";
    auto r = export_video_log(dir_ / "colour.vlog", o);
    ASSERT_FALSE(r.ok());
    EXPECT_EQ(r.error(), VideoLogError::kNoSuchPlane);
    EXPECT_FALSE(fs::exists(dir_ / "out"));
    EXPECT_FALSE(fs::exists(dir_ / "raw"));
    EXPECT_FALSE(fs::exists(dir_ / "out.mp4"));
  }
  // the image of the same log exports as before
  VideoLogExportOptions o = plain(VideoLogPlane::kImage);
  o.png_dir = dir_ / "image";
  auto r = export_video_log(dir_ / "colour.vlog", o);
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(r.value(), 2u);
}

TEST_F(VideoLogExportTest, OptionsOutOfRangeAreRefused) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  std::vector<VideoLogExportOptions> bad;
  for (double fps : {-1.0, nan, inf, 1000.5}) {
    bad.push_back(plain(VideoLogPlane::kDepth));
    bad.back().fps = fps;
  }
  for (auto [near_m, far_m] : {std::pair{0.0, 10.0},
                               {-1.0, 10.0},
                               {10.0, 10.0},
                               {10.0, 5.0},
                               {1.0, 2e6},
                               {nan, 10.0},
                               {1.0, inf}}) {
    bad.push_back(plain(VideoLogPlane::kDepth));
    bad.back().depth_near_m = near_m;
    bad.back().depth_far_m = far_m;
  }
  bad.push_back(plain(VideoLogPlane::kImage));
  bad.back().raw_dir = dir_ / "raw";  // the image has no exact form to dump
  for (size_t i = 0; i < bad.size(); ++i) {
    bad[i].png_dir = dir_ / "out";
    auto r = export_video_log(dir_ / "planes.vlog", bad[i]);
    ASSERT_FALSE(r.ok()) << i;
    EXPECT_EQ(r.error(), VideoLogError::kBadOption) << i;
    EXPECT_FALSE(fs::exists(dir_ / "out")) << i;
  }
  // the edges of the ranges are accepted
  VideoLogExportOptions edge = plain(VideoLogPlane::kDepth);
  edge.fps = kMaxExportFps;
  edge.depth_near_m = 1e-3;
  edge.depth_far_m = kMaxExportDepthM;
  edge.png_dir = dir_ / "edge";
  EXPECT_TRUE(export_video_log(dir_ / "planes.vlog", edge).ok());
}

}  // namespace
}  // namespace uavsim::vision
