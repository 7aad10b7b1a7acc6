// The video log a UAV program opens (missions/common/vehicle_camera.cpp); the camera's
// subscription needs a server and is covered by the missions' scenario tests.
#include "uavsim/mission/vehicle_camera.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <memory>
#include <regex>
#include <string>

namespace {

using uavsim::mission::open_video_log;
using uavsim::mission::ProgramLoop;
using uavsim::vision::VideoLogWriter;

TEST(OpenVideoLog, NoPathIsNoLog) {
  const auto program = ProgramLoop::create("uav0");
  ASSERT_NE(program, nullptr);
  std::unique_ptr<VideoLogWriter> vlog;
  EXPECT_TRUE(open_video_log(*program, "", &vlog));
  EXPECT_EQ(vlog, nullptr);
}

TEST(OpenVideoLog, AWritablePathIsOpened) {
  const auto program = ProgramLoop::create("uav0");
  ASSERT_NE(program, nullptr);
  const std::string path = testing::TempDir() + "open_video_log_test.vlog";
  std::unique_ptr<VideoLogWriter> vlog;
  EXPECT_TRUE(open_video_log(*program, path, &vlog));
  EXPECT_NE(vlog, nullptr);
  vlog.reset();
  std::remove(path.c_str());
}

// the launcher shows the program's last line as the reason it stopped
TEST(OpenVideoLog, AnUnwritablePathIsSaidInTheLog) {
  const auto program = ProgramLoop::create("uav1");
  ASSERT_NE(program, nullptr);
  std::unique_ptr<VideoLogWriter> vlog;
  testing::internal::CaptureStdout();
  EXPECT_FALSE(open_video_log(*program, "/nonexistent-dir/x.vlog", &vlog));
  const std::string out = testing::internal::GetCapturedStdout();
  EXPECT_EQ(vlog, nullptr);
  EXPECT_TRUE(std::regex_match(
      out, std::regex(R"(uav1 t=\d+\.\d\d --video-log /nonexistent-dir/x\.vlog: .+\n)")))
      << out;
}

}  // namespace
