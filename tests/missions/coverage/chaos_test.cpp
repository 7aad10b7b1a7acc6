// Chaos: a short coverage run (coverage-run, five quads on a small rectangle, a ground station)
// with one of its processes killed by SIGKILL at a seeded sim time: the server, an agent program,
// the ground station's program, or the launcher itself. Each case checks what a user finds
// afterwards: no process of the run left running, the run directory's logs readable up to the kill
// within their bounds (every line of events.jsonl is JSON, every tlog record a whole frame, every
// ground-truth row whole), the cause named in the launcher's output and its summary, and the exit
// code. Then an unusable run directory (under a file; on a full file system): a clear error at
// start. The kill moment is read from the launcher's progress lines (sim time); the waits are
// bounded polls whose bound only turns a hang into a failure.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/mount.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <nlohmann/json.hpp>
#include <optional>
#include <random>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "../support/run_process.hpp"

namespace {

using Json = nlohmann::json;
namespace fs = std::filesystem;
using uavsim::tests::events_of;
using uavsim::tests::expect_no_orphan;
using uavsim::tests::Proc;
using uavsim::tests::RunProcess;
constexpr double kTlogBound_s = 0.1;  // tlog.hpp: frames of the last 0.1 s of sim may be lost
constexpr std::uint64_t kSeed = 29;   // the issue's
constexpr double kFullCoverage = 0.999;

std::string read_file(const std::string& path) { return uavsim::tests::read_whole_file(path); }

// coverage-run as a child process, its output read as it comes
class ChaosRun {
 public:
  // before_exec: run in the launcher's process before its exec (limits it and all it starts)
  ChaosRun(const std::string& name, const std::vector<std::string>& extra,
           const std::function<void()>& before_exec = {})
      : dir_(::testing::TempDir() + "chaos-" + name + "-" + std::to_string(getpid())),
        run_(args(dir_, extra), before_exec) {}
  ~ChaosRun() {
    if (!::testing::Test::HasFailure()) fs::remove_all(dir_);
  }
  pid_t pid() const { return run_.pid(); }
  const std::string& dir() const { return dir_; }
  const std::string& output() const { return run_.output(); }
  int status() const { return run_.status(); }

  // reads output until the launcher's progress line says sim time t_s has passed; false if it
  // ended (or hung) first
  bool until_sim_time(double t_s) {
    static const std::regex progress(R"(coverage-run: t=(\d+) s coverage)");
    return run_.until([&] {
      const std::string& out = run_.output();
      for (auto it = std::sregex_iterator(out.begin(), out.end(), progress);
           it != std::sregex_iterator(); ++it) {
        if (std::stod((*it)[1]) >= t_s) {
          seen_s_ = std::stod((*it)[1]);
          return true;
        }
      }
      return false;
    });
  }
  // the last progress line's sim time at until_sim_time's return
  double seen_s() const { return seen_s_; }
  bool until_exit() { return run_.until_exit(); }
  std::vector<Proc> tree() const { return run_.tree(); }
  std::optional<Proc> find(const std::string& program, const std::string& arg = "") const {
    return run_.find(program, arg);
  }

 private:
  static std::vector<std::string> args(const std::string& dir,
                                       const std::vector<std::string>& extra) {
    fs::remove_all(dir);
    std::vector<std::string> a{
        COVERAGE_RUN,          "--agents",    "5",          "--area", "60x40",    "--seed",
        std::to_string(kSeed), "--no-record", "--progress", "1",      "--budget", "600",
        "--wall-limit",        "280",         "--run-dir",  dir};
    a.insert(a.end(), extra.begin(), extra.end());
    return a;
  }

  std::string dir_;
  RunProcess run_;
  double seen_s_ = -1.0;
};

int count_events(const Json& events, const std::string& kind) {
  return static_cast<int>(std::count_if(
      events.begin(), events.end(), [&](const Json& e) { return e.value("event", "") == kind; }));
}

// the newest stamp of a tlog whose records are all whole frames (an incomplete last record is the
// kill's residue); -1 for none
// (the bytes after the last whole record in *torn_bytes, if given)
double last_tlog_stamp_s(const std::string& path, size_t* torn_bytes = nullptr) {
  const std::string b = read_file(path);
  size_t at = 0;
  double last_s = -1.0;
  while (at + 8 + 3 <= b.size()) {
    std::uint64_t stamp = 0;
    for (int i = 0; i < 8; ++i) stamp = (stamp << 8) | static_cast<std::uint8_t>(b[at + i]);
    const auto* f = reinterpret_cast<const std::uint8_t*>(b.data() + at + 8);
    size_t len = 0;
    if (f[0] == 0xFE)
      len = 6 + size_t{f[1]} + 2;
    else if (f[0] == 0xFD)
      len = 10 + size_t{f[1]} + 2 + ((f[2] & 1) ? 13 : 0);
    EXPECT_NE(len, 0u) << path << ": not a frame at byte " << at;
    if (len == 0 || at + 8 + len > b.size()) break;
    last_s = stamp / 1e6;
    at += 8 + len;
  }
  EXPECT_LE(b.size() - at, 8u + 280u) << path << ": more than one record torn";
  if (torn_bytes != nullptr) *torn_bytes = b.size() - at;
  return last_s;
}

// every ground-truth row whole (16 fields), times rising; the last row's time
double last_truth_row_s(const std::string& path) {
  const std::string text = read_file(path);
  double last_s = -1.0;
  size_t at = text.find('\n') + 1;  // the header
  for (size_t nl; (nl = text.find('\n', at)) != std::string::npos; at = nl + 1) {
    const std::string row = text.substr(at, nl - at);
    EXPECT_EQ(std::count(row.begin(), row.end(), ','), 15) << path << ": " << row;
    const double t = std::stod(row);
    EXPECT_GT(t, last_s) << path;
    last_s = t;
  }
  return last_s;
}

// the seeded kill moment of case k: 20-40 s of sim (the quads are up and flying their stripes)
double kill_time_s(int k) {
  std::mt19937_64 rng(kSeed * 1000 + k);
  return std::uniform_int_distribution<int>(20, 40)(rng);
}

// the whole run directory after a kill at kill_seen_s: every log readable up to the kill
void expect_logs_readable_up_to(const std::string& dir, double kill_seen_s) {
  const Json events = events_of(dir);
  EXPECT_EQ(count_events(events, "takeoff"), 5) << dir;  // all five took off before the kill
  for (int i = 0; i < 5; ++i) {
    const std::string uav = "uav" + std::to_string(i);
    EXPECT_GE(last_tlog_stamp_s(dir + "/" + uav + ".tlog"), kill_seen_s - kTlogBound_s - 0.1)
        << uav;
    EXPECT_GE(last_truth_row_s(dir + "/truth_" + uav + ".csv"), kill_seen_s - 1.0) << uav;
  }
}

Json summary_of(const std::string& dir) {
  return Json::parse(read_file(dir + "/summary.json"), nullptr, false);
}

TEST(Chaos, ServerKilledTheCauseIsNamedTheHarnessFailedAndTheLogsHoldTheRunUpToTheKill) {
  ChaosRun run("server", {"--gcs"});
  ASSERT_TRUE(run.until_sim_time(kill_time_s(0))) << run.output();
  const auto server = run.find("uavsim-server", run.dir());
  ASSERT_TRUE(server) << run.output();
  const std::vector<Proc> snapshot = run.tree();
  ASSERT_EQ(kill(server->pid, SIGKILL), 0);
  ASSERT_TRUE(run.until_exit()) << run.output();
  EXPECT_TRUE(WIFEXITED(run.status()) && WEXITSTATUS(run.status()) == 4) << run.output();
  EXPECT_NE(run.output().find("server (pid " + std::to_string(server->pid) +
                              ") killed by SIGKILL at sim t="),
            std::string::npos)
      << run.output();
  expect_no_orphan(snapshot, run.dir());
  expect_logs_readable_up_to(run.dir(), run.seen_s());
  const Json s = summary_of(run.dir());
  ASSERT_TRUE(s.is_object()) << read_file(run.dir() + "/summary.json");
  EXPECT_NE(s.value("cause", Json()).dump().find("server killed by SIGKILL"), std::string::npos)
      << s.dump();
  EXPECT_FALSE(s["success"].get<bool>());
}

// the flock treats an agent whose program was killed as a failed agent: its quad is taken down and
// the others cover its stripes again
TEST(Chaos, AgentProgramKilledItIsAFailedAgentAndTheFlockStillCoversTheArea) {
  ChaosRun run("agent", {});
  ASSERT_TRUE(run.until_sim_time(kill_time_s(1))) << run.output();
  const auto agent = run.find("coverage-agent", "3-3");
  ASSERT_TRUE(agent) << run.output();
  const std::vector<Proc> snapshot = run.tree();
  ASSERT_EQ(kill(agent->pid, SIGKILL), 0);
  ASSERT_TRUE(run.until_exit()) << run.output();
  EXPECT_NE(run.output().find("agent3 (pid " + std::to_string(agent->pid) +
                              ") killed by SIGKILL at sim t="),
            std::string::npos)
      << run.output();
  expect_no_orphan(snapshot, run.dir());
  const Json s = summary_of(run.dir());
  ASSERT_TRUE(s.is_object()) << run.output();
  EXPECT_TRUE(s["complete"].get<bool>());
  EXPECT_NE(s.value("cause", Json()).dump().find("agent3 killed by SIGKILL"), std::string::npos)
      << s.dump();
  EXPECT_TRUE(s["per_agent"][3]["failed"].get<bool>()) << s.dump();
  EXPECT_GE(s["coverage"].get<double>(), kFullCoverage) << run.output();
  EXPECT_TRUE(s["success"].get<bool>()) << run.output();
  EXPECT_TRUE(WIFEXITED(run.status()) && WEXITSTATUS(run.status()) == 0) << run.output();
  EXPECT_GE(count_events(events_of(run.dir()), "vehicle_killed"), 1);
}

// the ground station is the variant's optimisation, not its safety: without it the flock covers
// the area from its own data
TEST(Chaos, GroundStationKilledTheCauseIsNamedAndTheFlockStillCoversTheArea) {
  ChaosRun run("gcs", {"--gcs"});
  ASSERT_TRUE(run.until_sim_time(kill_time_s(2))) << run.output();
  const auto gcs = run.find("coverage-gcs");
  ASSERT_TRUE(gcs) << run.output();
  const std::vector<Proc> snapshot = run.tree();
  ASSERT_EQ(kill(gcs->pid, SIGKILL), 0);
  ASSERT_TRUE(run.until_exit()) << run.output();
  EXPECT_NE(
      run.output().find("gcs (pid " + std::to_string(gcs->pid) + ") killed by SIGKILL at sim t="),
      std::string::npos)
      << run.output();
  expect_no_orphan(snapshot, run.dir());
  const Json s = summary_of(run.dir());
  ASSERT_TRUE(s.is_object()) << run.output();
  EXPECT_NE(s.value("cause", Json()).dump().find("gcs killed by SIGKILL"), std::string::npos)
      << s.dump();
  EXPECT_GE(s["coverage"].get<double>(), kFullCoverage) << run.output();
  EXPECT_TRUE(WIFEXITED(run.status()) && WEXITSTATUS(run.status()) == 0) << run.output();
}

// the launcher killed: the server and every program die with it (parent-death signal), and the
// run directory holds the run up to the kill, its summary marked incomplete
TEST(Chaos, LauncherKilledNoProcessOfTheRunSurvivesAndItsRecordsStay) {
  ChaosRun run("launcher", {"--gcs"});
  ASSERT_TRUE(run.until_sim_time(kill_time_s(3))) << run.output();
  const std::vector<Proc> snapshot = run.tree();
  ASSERT_GE(snapshot.size(), 7u);  // the server, five agents, the station
  ASSERT_EQ(kill(run.pid(), SIGKILL), 0);
  ASSERT_TRUE(run.until_exit());
  EXPECT_TRUE(WIFSIGNALED(run.status()) && WTERMSIG(run.status()) == SIGKILL);
  expect_no_orphan(snapshot, run.dir());
  expect_logs_readable_up_to(run.dir(), run.seen_s());
  const Json s = summary_of(run.dir());
  ASSERT_TRUE(s.is_object()) << read_file(run.dir() + "/summary.json");
  EXPECT_FALSE(s["complete"].get<bool>());
  EXPECT_EQ(s["mission"], "coverage");
  // rewritten every 10 s of sim: at most one period behind the kill
  EXPECT_GE(s["sim_time_s"].get<double>(), run.seen_s() - 10.0 - 1.0) << s.dump();
}

// A disk that fills up mid-run, without root: the launcher and everything it starts get a file
// size limit of 64 KiB (RLIMIT_FSIZE, SIGXFSZ ignored, so a write past it fails with EFBIG as one
// on a full disk fails with ENOSPC). The first log to reach it ends the run as a harness failure
// that names the file; every log keeps whole records up to where it stopped.
TEST(Chaos, ADiskFullMidRunEndsTheRunNamingTheFileAndKeepsWholeRecords) {
  constexpr rlim_t kFileLimitBytes = 64 * 1024;
  ChaosRun run("disk-full", {}, [] {
    signal(SIGXFSZ, SIG_IGN);
    const rlimit limit{kFileLimitBytes, kFileLimitBytes};
    (void)setrlimit(RLIMIT_FSIZE, &limit);
  });
  ASSERT_TRUE(run.until_sim_time(5.0)) << run.output();
  const std::vector<Proc> snapshot = run.tree();
  ASSERT_TRUE(run.until_exit()) << run.output();
  EXPECT_TRUE(WIFEXITED(run.status()) && WEXITSTATUS(run.status()) == 4) << run.output();
  EXPECT_NE(run.output().find("the run's records cannot be written: " + run.dir()),
            std::string::npos)
      << run.output();
  EXPECT_NE(run.output().find(": File too large at sim t="), std::string::npos) << run.output();
  expect_no_orphan(snapshot, run.dir());
  const Json s = summary_of(run.dir());
  ASSERT_TRUE(s.is_object()) << read_file(run.dir() + "/summary.json");
  EXPECT_TRUE(s["complete"].get<bool>()) << s.dump();
  EXPECT_FALSE(s["success"].get<bool>()) << s.dump();
  EXPECT_NE(s.value("records_error", Json()).dump().find("File too large"), std::string::npos)
      << s.dump();
  EXPECT_NE(s.value("cause", Json()).dump().find("the run's records cannot be written"),
            std::string::npos)
      << s.dump();
  // whole records in every log up to where it stopped: events, tlogs, ground truth
  events_of(run.dir());
  for (int i = 0; i < 5; ++i) {
    const std::string uav = "uav" + std::to_string(i);
    const std::string tlog = run.dir() + "/" + uav + ".tlog";
    EXPECT_LE(fs::file_size(tlog), kFileLimitBytes);
    size_t torn_bytes = 0;
    EXPECT_GT(last_tlog_stamp_s(tlog, &torn_bytes), 1.0) << uav;
    EXPECT_EQ(torn_bytes, 0u) << tlog << ": a frame cut at the limit";
    const std::string truth = run.dir() + "/truth_" + uav + ".csv";
    const std::string text = read_file(truth);
    ASSERT_FALSE(text.empty()) << truth;
    EXPECT_EQ(text.back(), '\n') << truth << ": a row cut at the limit";
    EXPECT_GT(last_truth_row_s(truth), 1.0) << uav;
  }
}

TEST(Chaos, ARunDirectoryUnderAFileIsAClearErrorAtStart) {
  const std::string file = ::testing::TempDir() + "chaos-a-file";
  std::ofstream(file) << "x";
  ChaosRun run("under-a-file", {"--run-dir", file + "/run"});
  ASSERT_TRUE(run.until_exit()) << run.output();
  EXPECT_TRUE(WIFEXITED(run.status()) && WEXITSTATUS(run.status()) == 2) << run.output();
  EXPECT_NE(run.output().find("cannot make the run directory " + file + "/run"), std::string::npos)
      << run.output();
}

// a file system with 64 KiB: refused at start with what is free and what a run needs
TEST(Chaos, AFullFileSystemIsAClearErrorAtStart) {
  const std::string mnt = ::testing::TempDir() + "chaos-tiny-fs-" + std::to_string(getpid());
  fs::create_directories(mnt);
  if (mount("tmpfs", mnt.c_str(), "tmpfs", 0, "size=64k") != 0) {
    const std::string why = std::strerror(errno);
    fs::remove(mnt);
    GTEST_SKIP() << "cannot mount a 64 KiB tmpfs here (" << why << "): needs CAP_SYS_ADMIN";
  }
  {
    ChaosRun run("full-fs", {"--run-dir", mnt + "/run"});
    ASSERT_TRUE(run.until_exit()) << run.output();
    EXPECT_TRUE(WIFEXITED(run.status()) && WEXITSTATUS(run.status()) == 2) << run.output();
    EXPECT_NE(run.output().find("KiB free; a run needs at least"), std::string::npos)
        << run.output();
  }
  umount(mnt.c_str());
  fs::remove_all(mnt);
}

}  // namespace
