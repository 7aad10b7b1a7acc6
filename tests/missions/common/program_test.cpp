// The start every mission program shares (missions/common/program.cpp).
#include "uavsim/mission/program.hpp"

#include <gtest/gtest.h>

#include <regex>
#include <string>

namespace {

using uavsim::mission::ProgramLoop;

// the launchers read the programs' lines by this shape ("uav1 t=3.65 Take-off -> ...")
TEST(ProgramLoop, LogLinesNameTheProgramAndTheLoopTime) {
  const auto program = ProgramLoop::create("uav7");
  ASSERT_NE(program, nullptr);
  testing::internal::CaptureStdout();
  program->log("ready: waiting for the GCS start");
  const std::string out = testing::internal::GetCapturedStdout();
  EXPECT_TRUE(
      std::regex_match(out, std::regex(R"(uav7 t=\d+\.\d\d ready: waiting for the GCS start\n)")))
      << out;
  EXPECT_EQ(program->name(), "uav7");
}

TEST(VehicleProgramOptions, TheSharedOptionsAreTakenOthersLeftToTheProgram) {
  uavsim::mission::VehicleProgramOptions o;
  using uavsim::mission::parse_vehicle_program_option;
  EXPECT_TRUE(parse_vehicle_program_option("--mavlink", "tcp:127.0.0.1:5760", &o));
  EXPECT_TRUE(parse_vehicle_program_option("--vehicle", "uav1", &o));
  EXPECT_TRUE(parse_vehicle_program_option("--camera", "uav1_front", &o));
  EXPECT_TRUE(parse_vehicle_program_option("--video-log", "v.vlog", &o));
  EXPECT_EQ(o.mavlink, "tcp:127.0.0.1:5760");
  EXPECT_EQ(o.vehicle, "uav1");
  EXPECT_EQ(o.camera, "uav1_front");
  EXPECT_EQ(o.video_log, "v.vlog");
  EXPECT_FALSE(parse_vehicle_program_option("--index", "1", &o));
  EXPECT_FALSE(parse_vehicle_program_option("--gcs", "127.0.0.1:1", &o));
}

TEST(ProgramLoop, NowUsIsTheLoopTimeInMicroseconds) {
  const auto program = ProgramLoop::create("gcs");
  ASSERT_NE(program, nullptr);
  const double before_s = program->loop().now();
  const int64_t now_us = program->now_us();
  const double after_s = program->loop().now();
  // whole microseconds of the loop's time, read between the two
  EXPECT_GE(now_us, static_cast<int64_t>(before_s * 1e6) - 1);
  EXPECT_LE(now_us, static_cast<int64_t>(after_s * 1e6) + 1);
}

}  // namespace
