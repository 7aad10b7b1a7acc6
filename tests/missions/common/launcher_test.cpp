// Launcher with /bin/sh children: their output as prefixed lines (stdout and stderr, a last line
// without its newline), the environment, programs_done, stop_all ending a running program, and a
// server that exits before it serves the API.
#include "uavsim/launch/launcher.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace uavsim::launch {
namespace {

constexpr int kPumpMs = 50;
constexpr double kWallLimit_s = 10.0;  // for programs that end at once

TEST(Launcher, ChildrensLinesReachOnLineInOrder) {
  Launcher launch("test", true);
  std::vector<std::pair<std::string, std::string>> lines;
  launch.on_line(
      [&](const std::string& child, const std::string& line) { lines.emplace_back(child, line); });
  ASSERT_TRUE(launch.spawn("sh", {"/bin/sh", "-c", "echo one; echo two >&2; printf three"}));
  while (!launch.programs_done() && launch.wall_s() < kWallLimit_s) launch.pump(kPumpMs);
  EXPECT_TRUE(launch.programs_done());
  const std::vector<std::pair<std::string, std::string>> want{
      {"sh", "one"}, {"sh", "two"}, {"sh", "three"}};
  EXPECT_EQ(lines, want);
}

TEST(Launcher, EnvironmentGetsTheExtrasAndNoInheritedLockstep) {
  setenv("UAVSIM_LOCKSTEP", "127.0.0.1:1/0.1", 1);
  Launcher launch("test", true);
  std::vector<std::string> lines;
  launch.on_line([&](const std::string&, const std::string& line) { lines.push_back(line); });
  ASSERT_TRUE(
      launch.spawn("sh", {"/bin/sh", "-c", "echo \"[$UAVSIM_LOCKSTEP][$EXTRA]\""}, {"EXTRA=x"}));
  while (!launch.programs_done() && launch.wall_s() < kWallLimit_s) launch.pump(kPumpMs);
  unsetenv("UAVSIM_LOCKSTEP");
  EXPECT_EQ(lines, std::vector<std::string>{"[][x]"});
}

TEST(Launcher, StopAllEndsRunningPrograms) {
  Launcher launch("test", true);
  ASSERT_TRUE(launch.spawn("sleeper", {"/bin/sleep", "100"}));
  launch.pump(0);
  EXPECT_FALSE(launch.programs_done());
  launch.stop_all(2.0);
  EXPECT_TRUE(launch.programs_done());
  EXPECT_LT(launch.wall_s(), kWallLimit_s);
}

TEST(Launcher, MissingProgramIsAFailure) {
  Launcher launch("test", true);
  const auto r = launch.spawn("none", {"/nonexistent/program"});
  EXPECT_FALSE(r);
}

TEST(Launcher, ServerThatExitsBeforeServingTheApiIsAFailure) {
  Launcher launch("test", true);
  ServerSpec spec;
  spec.path = "/bin/true";
  spec.world = "world.xml";
  spec.start_timeout_s = kWallLimit_s;
  const auto r = launch.start_server(spec);
  ASSERT_FALSE(r);
  EXPECT_NE(r.message().find("exited"), std::string::npos) << r.message();
  EXPECT_EQ(launch.api_port(), 0);
  EXPECT_EQ(launch.mavlink_port("uav0"), 0);
}

TEST(Launcher, SiblingProgramIsBesideThisExecutable) {
  const std::string p = sibling_program("x");
  EXPECT_EQ(p.substr(p.size() - 2), "/x");
  EXPECT_NE(p.find("/tests/missions/common/"), std::string::npos) << p;
}

TEST(Launcher, DefaultRunDirNamesMissionSeedAndTime) {
  const std::string d = default_run_dir("mbzirc2020", 7);
  EXPECT_EQ(d.rfind("runs/mbzirc2020-seed7-", 0), 0u) << d;
  EXPECT_EQ(d.size(), std::string("runs/mbzirc2020-seed7-YYYYMMDD-HHMMSS").size()) << d;
  std::string why;
  EXPECT_TRUE(make_run_dir(::testing::TempDir() + "a/b/run", &why)) << why;
  EXPECT_FALSE(make_run_dir("/proc/no/such/run", &why));
  EXPECT_FALSE(why.empty());
}

// the run files from a launcher's options (the "auto" default makes a directory under ./runs, so
// it is not exercised here: the test leaves nothing behind)
TEST(Launcher, RunFilesGoIntoTheRunDirectoryUnlessGivenOrOptedOut) {
  const std::string dir = ::testing::TempDir() + "run_files/r1";
  auto f = resolve_run_files("m", 1, dir, "", "", true);
  ASSERT_TRUE(f) << f.message();
  EXPECT_EQ(f->dir, dir);
  EXPECT_EQ(f->video, dir + "/video.mp4");
  EXPECT_EQ(f->summary, dir + "/summary.json");
  EXPECT_TRUE(std::filesystem::is_directory(dir));
  // --record / --json given: kept; --no-record: no video
  f = resolve_run_files("m", 1, dir, "/tmp/v.mp4", "/tmp/s.json", true);
  EXPECT_EQ(f->video, "/tmp/v.mp4");
  EXPECT_EQ(f->summary, "/tmp/s.json");
  EXPECT_EQ(resolve_run_files("m", 1, dir, "", "", false)->video, "");
  // --no-run-dir: nothing unless given
  f = resolve_run_files("m", 1, "none", "", "", true);
  EXPECT_EQ(f->dir, "");
  EXPECT_EQ(f->video, "");
  EXPECT_EQ(f->summary, "");
  EXPECT_EQ(resolve_run_files("m", 1, "none", "/tmp/v.mp4", "", true)->video, "/tmp/v.mp4");
  // a directory that cannot be made
  EXPECT_FALSE(resolve_run_files("m", 1, "/proc/no/such/run", "", "", true));
}

#ifdef UAVSIM_SERVER_BIN
constexpr double kServerWall_s = 60.0;  // a server on a loaded machine

// the ground truth of a run: a mission client on the lockstep for 2 s of sim time; the launcher's own
// connection samples every vehicle at 10 Hz at exact sim times, then leaves when the client has left
TEST(Launcher, RecordsGroundTruthAtItsRateWhileTheMissionRuns) {
  Launcher launch("test", true);
  ServerSpec spec;
  spec.path = UAVSIM_SERVER_BIN;
  spec.world = std::string(UAVSIM_MODELS_DIR) + "/worlds/mbzirc2020.xml";
  spec.extra_args = {"--no-cameras"};
  spec.start_timeout_s = kServerWall_s;
  ASSERT_TRUE(launch.start_server(spec));
  const std::string dir = ::testing::TempDir() + "truth_run";
  std::string why;
  ASSERT_TRUE(make_run_dir(dir, &why)) << why;
  launch.record_truth(dir, 10.0);
  // the server runs from its start: hold it and go back to t = 0, as the launchers do
  ASSERT_TRUE(launch.api().pause());
  ASSERT_TRUE(launch.api().reset(1));
  auto client = client::SimConnection::connect("127.0.0.1", static_cast<uint16_t>(launch.api_port()));
  ASSERT_TRUE(client);
  ASSERT_TRUE((*client)->lockstep_join(0.05, kServerWall_s));
  ASSERT_TRUE(launch.wait_lockstep_clients(1, kServerWall_s));
  ASSERT_TRUE(launch.api().resume());
  double t = 0.0;
  while (t < 2.0 && launch.wall_s() < kServerWall_s) {
    launch.pump(0);
    ASSERT_TRUE((*client)->poll(5));
    for (const client::SimMessage& m : (*client)->take_messages()) {
      if (m.kind() != "tick") continue;
      t = m.json.value("time", 0.0);
      ASSERT_TRUE((*client)->done(m.json.value("tick", int64_t{0})));
    }
  }
  ASSERT_TRUE((*client)->lockstep_leave());
  for (int i = 0; i < 20; ++i) launch.pump(10);
  launch.stop_all(10.0);

  // truth_uav0.csv: a header, then rows 0.1 s of sim time apart up to about 2 s
  std::ifstream f(dir + "/truth_uav0.csv");
  ASSERT_TRUE(f) << dir;
  std::string line;
  std::getline(f, line);
  EXPECT_EQ(line.rfind("t_s,x_m,y_m,z_m,vx_m_s", 0), 0u) << line;
  std::vector<double> times;
  while (std::getline(f, line)) times.push_back(std::stod(line));
  // ticks 0.1 .. 1.9 s: the one at 2 s finds the client gone and leaves instead
  ASSERT_GE(times.size(), 19u);
  EXPECT_LE(times[0], 0.1 + 1e-6);  // the first tick after joining
  for (size_t i = 1; i < times.size(); ++i) EXPECT_NEAR(times[i] - times[i - 1], 0.1, 1e-6) << i;
  EXPECT_GE(times.back(), 1.9 - 1e-6);
  EXPECT_GE(launch.truth_rows(), 2 * times.size() - 2);  // both quads
}
#endif

}  // namespace
}  // namespace uavsim::launch
