// Launcher with /bin/sh children: their output as prefixed lines (stdout and stderr, a last line
// without its newline), the environment, programs_done, stop_all ending a running program, and a
// server that exits before it serves the API.
#include "uavsim/launch/launcher.hpp"

#include <gtest/gtest.h>

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

}  // namespace
}  // namespace uavsim::launch
