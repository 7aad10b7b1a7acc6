// uavsim-videolog-export, the program: the planes of a version 2 log exported through its options,
// every option range-checked (exit 2 and a message naming it), and a log without the plane asked
// for refused naming what the log holds (exit 1), with nothing written.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <string>

#include "plane_log.hpp"
#include "../support/run_command.hpp"

namespace uavsim::vision {
namespace {

namespace fs = std::filesystem;

using ExportRun = uavsim::testing::CommandRun;
using uavsim::testing::has;

ExportRun run_export(const std::string& args) {
  return uavsim::testing::run_command(std::string(UAVSIM_VIDEOLOG_EXPORT_BIN) + " " + args);
}

class VideologExportCli : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() /
           (std::string("uavsim_vlog_cli_") + info->name() + "_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    ASSERT_TRUE(test::write_plane_log(dir_ / "planes.vlog", 3));
    ASSERT_TRUE(test::write_plane_log(dir_ / "colour.vlog", 2, false));
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string path(const std::string& name) const { return "'" + (dir_ / name).string() + "'"; }
  fs::path dir_;
};

TEST_F(VideologExportCli, ExportsEachPlaneAsPicturesAndRawDumps) {
  ExportRun r = run_export(
      path("planes.vlog") + " --plane depth --depth-near 2 --depth-far 40 --png " + path("d") +
      " --raw " + path("draw") + " --mp4 " + path("d.mp4") + " --fps 10 --no-text");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(has(r, "exported 3 frames (depth)")) << r.output;
  EXPECT_TRUE(fs::exists(dir_ / "d" / "frame_000002.png"));
  EXPECT_TRUE(fs::exists(dir_ / "d.mp4"));
  const test::Npy npy = test::read_npy(dir_ / "draw" / "depth_000002.npy");
  EXPECT_EQ(npy.descr, "<f4");
  EXPECT_EQ(npy.data, test::mat_bytes(test::plane_frame(2).depth_m));
  // --depth-near 2: z = 1 m and 2 m are both drawn as near, z = 40 m (x = 39) as far
  const cv::Mat png = cv::imread((dir_ / "d" / "frame_000000.png").string());
  EXPECT_EQ(png.at<cv::Vec3b>(1, 0), png.at<cv::Vec3b>(1, 1));
  EXPECT_NE(png.at<cv::Vec3b>(1, 1), png.at<cv::Vec3b>(1, 2));
  EXPECT_EQ(png.at<cv::Vec3b>(1, 39), png.at<cv::Vec3b>(6, 39));  // 40 m and 500 m: far

  for (const char* plane : {"objects", "classes"}) {
    r = run_export(path("planes.vlog") + " --plane " + plane + " --raw " + path(plane));
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_TRUE(has(r, std::string("exported 3 frames (") + plane + ")")) << r.output;
    const test::Npy ids = test::read_npy(dir_ / plane / (std::string(plane) + "_000001.npy"));
    EXPECT_EQ(ids.descr, "<u2");
    const VideoLogFrame f = test::plane_frame(1);
    EXPECT_EQ(ids.data,
              test::mat_bytes(std::string(plane) == "objects" ? f.object_ids : f.class_ids));
  }

  r = run_export(path("planes.vlog") + " --info");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(has(r, "3 frames")) << r.output;
  EXPECT_TRUE(has(r, "image+depth+objects+classes")) << r.output;
}

TEST_F(VideologExportCli, ALogWithoutThePlaneIsRefusedNamingWhatItHas) {
  const ExportRun r = run_export(path("colour.vlog") + " --plane classes --png " + path("out"));
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_TRUE(has(r, "a frame without the plane asked for (classes; the log has image)"))
      << r.output;
  EXPECT_FALSE(fs::exists(dir_ / "out"));
  // its image exports as it always did
  EXPECT_EQ(run_export(path("colour.vlog") + " --png " + path("image")).exit_code, 0);
}

TEST_F(VideologExportCli, OptionsOutOfRangeAreUsageErrors) {
  const std::string log = path("planes.vlog") + " --png " + path("out") + " ";
  const std::pair<const char*, const char*> bad[] = {
      {"--plane thermal", "image, depth, objects or classes"},
      {"--plane", "--plane (missing)"},
      {"--fps 0", "(0, 1000]"},
      {"--fps 12abc", "(0, 1000]"},
      {"--depth-near 0", "(0, 1e6]"},
      {"--depth-far 2e6", "(0, 1e6]"},
      {"--depth-near 5 --depth-far 2", "--depth-near 5 must be below --depth-far 2"},
      {"--raw x", "--raw needs --plane depth, objects or classes"},
  };
  // (the library refuses the same ranges at their edges: video_log_export_test.cpp)
  for (const auto& [args, message] : bad) {
    const ExportRun r = run_export(log + args);
    EXPECT_EQ(r.exit_code, 2) << args << ": " << r.output;
    EXPECT_TRUE(has(r, message)) << args << ": " << r.output;
  }
  EXPECT_FALSE(fs::exists(dir_ / "out"));
}

}  // namespace
}  // namespace uavsim::vision
