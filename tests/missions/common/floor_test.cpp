// A mission's floor (--floor S, launch::run_floor): each launcher runs the server its mission
// would, for S sim seconds, with no program and no client, its vehicles hovering and the cameras
// its programs subscribe to rendered. What the server did is read back from its closing report,
// which the summary keeps.
#include <gtest/gtest.h>

#include <cctype>
#include <cstdio>
#include <cstdlib>
#include <nlohmann/json.hpp>
#include <string>

#include "../../support/run_command.hpp"
#include "../support/launcher_run.hpp"

namespace {

using Json = nlohmann::json;
using uavsim::testing::run_command;
using uavsim::tests::run_launcher;

// The number in the server's report just before " what" ("1 vehicle(s)": 1); -1 if none.
long report_count(const Json& summary, const std::string& what) {
  const std::string report = summary.value("server_report", std::string());
  const size_t at = report.find(" " + what);
  if (at == std::string::npos) return -1;
  size_t begin = at;
  while (begin > 0 && std::isdigit(static_cast<unsigned char>(report[begin - 1]))) --begin;
  if (begin == at) return -1;
  return std::strtol(report.substr(begin, at - begin).c_str(), nullptr, 10);
}

// A floor that ran its whole span, vehicles hovering (none crashed) and no client connected.
void expect_a_whole_floor(const Json& s, const std::string& mission, double span_s, long vehicles,
                          const std::string& output) {
  ASSERT_TRUE(s.is_object()) << output;
  EXPECT_EQ(s.value("mission", ""), mission) << output;
  EXPECT_TRUE(s.value("floor", false)) << output;
  EXPECT_TRUE(s.value("success", false)) << output;
  EXPECT_TRUE(s.value("complete", false)) << output;
  EXPECT_DOUBLE_EQ(s.value("sim_time_s", -1.0), span_s) << output;
  EXPECT_GT(s.value("wall_time_s", 0.0), 0.0) << output;
  EXPECT_EQ(report_count(s, "vehicle(s)"), vehicles) << s.dump(1);
  EXPECT_EQ(report_count(s, "crash(es)"), 0) << s.dump(1);
  EXPECT_EQ(report_count(s, "MAVLink client connection(s)"), 0) << s.dump(1);
  char ran[64];
  std::snprintf(ran, sizeof(ran), "ran %.3f s of sim time", span_s);
  EXPECT_NE(s.value("server_report", std::string()).find(ran), std::string::npos) << s.dump(1);
  EXPECT_NE(output.find("floor: sim time"), std::string::npos) << output;
}

TEST(MissionFloor, Mbzirc2017RendersItsUavsDownwardCameraWithNoProgram) {
  std::string output;
  const Json s = run_launcher(MBZIRC2017_RUN, "--no-record --floor 3", &output);
  expect_a_whole_floor(s, "mbzirc2017", 3.0, 1, output);
  EXPECT_EQ(s.value("render_cameras", ""), "uav0_down:grey");
  // the world's 7 frames a sim second, grey, for 3 s
  EXPECT_NE(s.value("server_report", std::string()).find("(uav0_down 21 at 7 fps grey)"),
            std::string::npos)
      << s.dump(1);
}

TEST(MissionFloor, Mbzirc2020RendersBothForwardCamerasAtTheMissionsSize) {
  std::string output;
  const Json s = run_launcher(MBZIRC2020_RUN, "--no-record --floor 2 --camera-fps 5", &output);
  expect_a_whole_floor(s, "mbzirc2020", 2.0, 2, output);
  // the launcher's camera settings (--camera-fps here) reach the floor's server as the mission's
  EXPECT_EQ(report_count(s, "camera frames rendered"), 20) << s.dump(1);
  for (const char* cam : {"uav0_front 10 at 5 fps", "uav1_front 10 at 5 fps"})
    EXPECT_NE(s.value("server_report", std::string()).find(cam), std::string::npos) << s.dump(1);
}

TEST(MissionFloor, CoverageFliesItsGeneratedWorldsQuadsWithNoCamera) {
  std::string output;
  const Json s =
      run_launcher(COVERAGE_RUN, "--no-record --agents 3 --area 100x60 --floor 2", &output);
  expect_a_whole_floor(s, "coverage", 2.0, 3, output);
  EXPECT_EQ(report_count(s, "camera frames rendered"), -1) << s.dump(1);
}

TEST(MissionFloor, ASpanOutOfRangeIsAUsageError) {
  for (const char* launcher : {MBZIRC2017_RUN, MBZIRC2020_RUN, COVERAGE_RUN}) {
    for (const char* span : {"0", "-1", "nan", "inf", "2e6", "x"}) {
      const auto r = run_command(std::string(launcher) + " --no-run-dir --floor " + span);
      EXPECT_EQ(r.exit_code, 2) << launcher << " --floor " << span << ": " << r.output;
      EXPECT_NE(r.output.find("--floor S"), std::string::npos) << r.output;  // the usage says it
    }
  }
}

TEST(MissionFloor, AServerThatDoesNotRunTheSpanIsAHarnessFailure) {
  std::string output;
  const Json s = run_launcher(MBZIRC2017_RUN, "--no-record --floor 3 --server /bin/true", &output);
  ASSERT_TRUE(s.is_object()) << output;
  EXPECT_FALSE(s.value("success", true)) << s.dump(1);
  EXPECT_EQ(s.value("sim_time_s", 0.0), -1.0) << s.dump(1);
  const auto r = run_command(std::string(MBZIRC2017_RUN) +
                             " --no-record --no-run-dir --floor 3 --server /bin/true");
  EXPECT_EQ(r.exit_code, 4) << r.output;
  EXPECT_NE(r.output.find("floor: the server did not start"), std::string::npos) << r.output;
}

}  // namespace
