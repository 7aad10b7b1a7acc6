// Launcher with /bin/sh children: their output as prefixed lines (stdout and stderr, a last line
// without its newline), the environment, programs_done, stop_all ending a running program, a
// server that exits before it serves the API, the process group the programs share and their
// death with a killed launcher, and how each program ended, named in the summary.
#include "uavsim/launch/launcher.hpp"

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
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

// a process's state letter and process group from /proc/PID/stat; 0 when it is gone
std::pair<char, pid_t> proc_state(pid_t pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/stat");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const size_t paren = text.rfind(')');
  if (paren == std::string::npos) return {0, 0};
  std::istringstream rest(text.substr(paren + 2));
  char state = 0;
  long ppid = 0, pgrp = 0;
  rest >> state >> ppid >> pgrp;
  return {state, static_cast<pid_t>(pgrp)};
}
bool gone(pid_t pid) {
  const char state = proc_state(pid).first;
  return state == 0 || state == 'Z' || state == 'X';  // a zombie has died (its reaper is init)
}

// a launcher in a child process starts two programs that would run for minutes, writes their pids
// and group to the test, and is killed with SIGKILL: both programs die with it
TEST(Launcher, ProgramsShareAGroupOfTheirOwnAndDieWithAKilledLauncher) {
  int out[2];
  ASSERT_EQ(pipe(out), 0);
  const pid_t launcher = fork();
  if (launcher == 0) {
    close(out[0]);
    Launcher launch("test", true);
    if (!launch.spawn("a", {"/bin/sleep", "300"}) ||
        // exec: the shell becomes the program (a shell that forks it would leave a grandchild, which
        // the parent-death signal of the launcher's own children does not reach)
        !launch.spawn("b", {"/bin/sh", "-c", "exec sleep 300"}))
      _exit(1);
    launch.pump(0);
    const std::string group = std::to_string(launch.process_group());
    (void)!write(out[1], group.data(), group.size());
    close(out[1]);
    for (;;) pause();
  }
  close(out[1]);
  std::string text;
  char buf[64];
  for (ssize_t n; (n = read(out[0], buf, sizeof(buf))) > 0;)
    text.append(buf, static_cast<size_t>(n));
  close(out[0]);
  const pid_t group = static_cast<pid_t>(std::stol(text));
  ASSERT_GT(group, 0);
  ASSERT_NE(group, getpgrp());  // not the test's (nor the launcher's) group
  // the group's members: the launcher's children
  std::vector<pid_t> members;
  for (const auto& e : std::filesystem::directory_iterator("/proc")) {
    const std::string n = e.path().filename();
    if (n.find_first_not_of("0123456789") != std::string::npos) continue;
    const pid_t pid = static_cast<pid_t>(std::stol(n));
    if (proc_state(pid).second == group && !gone(pid)) members.push_back(pid);
  }
  EXPECT_GE(members.size(), 2u);
  ASSERT_EQ(kill(launcher, SIGKILL), 0);
  int status = 0;
  ASSERT_EQ(waitpid(launcher, &status, 0), launcher);
  // the kernel delivers the parent-death signal as the launcher exits: poll, bounded
  const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  auto all_gone = [&] { return std::all_of(members.begin(), members.end(), gone); };
  while (!all_gone() && std::chrono::steady_clock::now() < end) usleep(10000);
  for (pid_t pid : members) EXPECT_TRUE(gone(pid)) << "pid " << pid << " outlived its launcher";
}

TEST(Launcher, NamesHowEachProgramEndedWithTheSimTimeAndKeepsItInTheSummary) {
  const std::string summary = ::testing::TempDir() + "ends_summary.json";
  Launcher launch("test", true);
  launch.keep_summary(summary, {{"mission", "test"}});
  std::vector<ProgramEnd> ends;
  launch.on_exit([&](const ProgramEnd& e) { ends.push_back(e); });
  // the first summary is there before anything ran, marked incomplete
  {
    const auto j = nlohmann::json::parse(std::ifstream(summary));
    EXPECT_EQ(j["mission"], "test");
    EXPECT_FALSE(j["complete"].get<bool>());
  }
  launch.note_sim_time(12.5);
  ASSERT_TRUE(launch.spawn("killed", {"/bin/sh", "-c", "kill -KILL $$"}));
  ASSERT_TRUE(launch.spawn("failed", {"/bin/sh", "-c", "exit 3"}));
  ASSERT_TRUE(launch.spawn("fine", {"/bin/true"}));
  while (!launch.programs_done() && launch.wall_s() < kWallLimit_s) launch.pump(kPumpMs);
  ASSERT_EQ(ends.size(), 3u);
  const auto killed = launch.ended("killed");
  ASSERT_TRUE(killed);
  EXPECT_EQ(killed->signal, SIGKILL);
  EXPECT_TRUE(killed->abnormal());
  EXPECT_EQ(killed->how.rfind("killed by SIGKILL", 0), 0u) << killed->how;
  EXPECT_NE(killed->how.find("at sim t=12.50 s"), std::string::npos) << killed->how;
  EXPECT_EQ(launch.ended("failed")->exit_code, 3);
  EXPECT_EQ(launch.ended("failed")->how, "exited with code 3 at sim t=12.50 s");
  EXPECT_FALSE(launch.ended("fine")->abnormal());
  // the summary so far: every end, the first abnormal one as the cause
  const auto j = nlohmann::json::parse(std::ifstream(summary));
  EXPECT_FALSE(j["complete"].get<bool>());
  ASSERT_EQ(j["programs"].size(), 3u);
  EXPECT_NE(j["cause"].get<std::string>().find("SIGKILL"), std::string::npos) << j.dump();
  EXPECT_EQ(j["sim_time_s"].get<double>(), 12.5);
  // the final one replaces it, complete
  ASSERT_TRUE(launch.write_summary(summary, {{"mission", "test"}, {"success", false}}));
  const auto f = nlohmann::json::parse(std::ifstream(summary));
  EXPECT_TRUE(f["complete"].get<bool>());
  EXPECT_EQ(f["programs"][1]["exit_code"], 3);
}

// A mission program whose vision log the disk refuses says so in one line; the launcher takes it as
// the run's first lost record, with the sim time. A program that only echoes the server's words is
// not the server: its line is not a lost record.
TEST(Launcher, AProgramsVisionLogThatStopsIsALostRecord) {
  Launcher launch("test", true);
  launch.note_sim_time(3.0);
  ASSERT_TRUE(
      launch.spawn("impostor", {"/bin/sh", "-c", "echo 'uavsim-server: the tlog stops here: x'"}));
  while (!launch.programs_done() && launch.wall_s() < kWallLimit_s) launch.pump(kPumpMs);
  EXPECT_EQ(launch.records_error(), "");
  ASSERT_TRUE(launch.spawn(
      "uav0",
      {"/bin/sh", "-c", "echo 'uav0: the vision log stops here: /r/uav0.vlog: File too large'"}));
  while (!launch.programs_done() && launch.wall_s() < kWallLimit_s) launch.pump(kPumpMs);
  EXPECT_EQ(launch.records_error(), "/r/uav0.vlog: File too large at sim t=3.00 s");
}

TEST(Launcher, TheSummaryIsRewrittenEveryPeriodOfSimTime) {
  const std::string summary = ::testing::TempDir() + "periodic_summary.json";
  Launcher launch("test", true);
  launch.keep_summary(summary, {{"mission", "test"}});
  auto sim_time_in_file = [&] {
    return nlohmann::json::parse(std::ifstream(summary))["sim_time_s"].get<double>();
  };
  launch.note_sim_time(Launcher::kSummaryPeriod_s - 0.5);
  EXPECT_EQ(sim_time_in_file(), -1.0);  // not yet a period
  launch.note_sim_time(Launcher::kSummaryPeriod_s);
  EXPECT_EQ(sim_time_in_file(), Launcher::kSummaryPeriod_s);
  launch.update_summary({{"progress", 0.5}});
  launch.note_sim_time(2 * Launcher::kSummaryPeriod_s + 1.0);
  const auto j = nlohmann::json::parse(std::ifstream(summary));
  EXPECT_EQ(j["sim_time_s"].get<double>(), 2 * Launcher::kSummaryPeriod_s + 1.0);
  EXPECT_EQ(j["progress"].get<double>(), 0.5);
}

TEST(Launcher, ARunDirectoryUnderAFileIsAClearErrorAtStart) {
  const std::string file = ::testing::TempDir() + "run_dir_parent_is_a_file";
  std::ofstream(file) << "x";
  std::string why;
  EXPECT_FALSE(make_run_dir(file + "/run", &why));
  EXPECT_NE(why.find("cannot make the run directory " + file + "/run"), std::string::npos) << why;
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
constexpr double kTickTol_s = 1e-6;     // sim times of whole steps

// the ground truth of a run: a mission client on the lockstep for 2 s of sim time; the launcher's
// own connection samples every vehicle at 10 Hz at exact sim times, then leaves when the client has
// left
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
  auto client =
      client::SimConnection::connect("127.0.0.1", static_cast<uint16_t>(launch.api_port()));
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
  for (size_t i = 1; i < times.size(); ++i)
    EXPECT_NEAR(times[i] - times[i - 1], 0.1, kTickTol_s) << i;
  EXPECT_GE(times.back(), 1.9 - 1e-6);
  EXPECT_GE(launch.truth_rows(), 2 * times.size() - 2);  // both quads
}
#endif

}  // namespace
}  // namespace uavsim::launch
