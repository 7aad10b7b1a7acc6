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
#include <poll.h>
#include <signal.h>
#include <sys/mount.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <optional>
#include <random>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

namespace {

using Json = nlohmann::json;
using Clock = std::chrono::steady_clock;
namespace fs = std::filesystem;

constexpr double kWallBound_s = 300.0;  // a hang, not a slow machine
constexpr double kTlogBound_s = 0.1;    // tlog.hpp: frames of the last 0.1 s of sim may be lost
constexpr std::uint64_t kSeed = 29;     // the issue's
constexpr double kFullCoverage = 0.999;

std::string read_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

// a process's argv and parent, from /proc
struct Proc {
  pid_t pid = 0;
  pid_t ppid = 0;
  pid_t pgrp = 0;
  char state = 0;
  std::vector<std::string> argv;
};
std::optional<Proc> read_proc(pid_t pid) {
  const std::string dir = "/proc/" + std::to_string(pid);
  const std::string stat = read_file(dir + "/stat");
  const size_t paren = stat.rfind(')');
  if (paren == std::string::npos) return std::nullopt;
  Proc p;
  p.pid = pid;
  long ppid = 0, pgrp = 0;
  std::istringstream rest(stat.substr(paren + 2));
  rest >> p.state >> ppid >> pgrp;
  p.ppid = static_cast<pid_t>(ppid);
  p.pgrp = static_cast<pid_t>(pgrp);
  std::string cmd = read_file(dir + "/cmdline");
  for (size_t a = 0; a < cmd.size();) {
    const size_t z = cmd.find('\0', a);
    p.argv.push_back(cmd.substr(a, z == std::string::npos ? std::string::npos : z - a));
    if (z == std::string::npos) break;
    a = z + 1;
  }
  return p;
}
std::vector<Proc> all_procs() {
  std::vector<Proc> out;
  for (const auto& e : fs::directory_iterator("/proc")) {
    const std::string n = e.path().filename();
    if (n.find_first_not_of("0123456789") != std::string::npos) continue;
    if (auto p = read_proc(static_cast<pid_t>(std::stol(n)))) out.push_back(*p);
  }
  return out;
}
bool alive(const Proc& p) { return p.state != 0 && p.state != 'Z' && p.state != 'X'; }

// coverage-run as a child process, its output read as it comes
class ChaosRun {
 public:
  ChaosRun(const std::string& name, const std::vector<std::string>& extra) {
    dir_ = ::testing::TempDir() + "chaos-" + name + "-" + std::to_string(getpid());
    fs::remove_all(dir_);
    std::vector<std::string> args{
        COVERAGE_RUN,          "--agents",    "5",          "--area", "60x40",    "--seed",
        std::to_string(kSeed), "--no-record", "--progress", "1",      "--budget", "600",
        "--wall-limit",        "280",         "--run-dir",  dir_};
    args.insert(args.end(), extra.begin(), extra.end());
    int fds[2];
    if (pipe(fds) != 0) return;
    pid_ = fork();
    if (pid_ == 0) {
      dup2(fds[1], 1);
      dup2(fds[1], 2);
      close(fds[0]);
      close(fds[1]);
      std::vector<char*> argv;
      for (auto& a : args) argv.push_back(a.data());
      argv.push_back(nullptr);
      execv(argv[0], argv.data());
      _exit(127);
    }
    close(fds[1]);
    fd_ = fds[0];
  }
  ~ChaosRun() {
    if (pid_ > 0 && !exited_) {
      kill(pid_, SIGKILL);
      waitpid(pid_, &status_, 0);
    }
    if (fd_ >= 0) close(fd_);
    if (!::testing::Test::HasFailure()) fs::remove_all(dir_);
  }
  pid_t pid() const { return pid_; }
  const std::string& dir() const { return dir_; }
  const std::string& output() const { return output_; }
  int status() const { return status_; }

  // reads output until the launcher's progress line says sim time t_s has passed; false if it
  // ended (or hung) first
  bool until_sim_time(double t_s) {
    static const std::regex progress(R"(coverage-run: t=(\d+) s coverage)");
    const auto end = Clock::now() + std::chrono::duration<double>(kWallBound_s);
    while (Clock::now() < end) {
      std::smatch m;
      for (auto it = std::sregex_iterator(output_.begin(), output_.end(), progress);
           it != std::sregex_iterator(); ++it) {
        if (std::stod((*it)[1]) >= t_s) {
          seen_s_ = std::stod((*it)[1]);
          return true;
        }
      }
      if (!read_some()) return false;
    }
    return false;
  }
  // the last progress line's sim time at until_sim_time's return
  double seen_s() const { return seen_s_; }
  // reads all output until the launcher exits; false if it does not within the bound
  bool until_exit() {
    const auto end = Clock::now() + std::chrono::duration<double>(kWallBound_s);
    while (read_some() && Clock::now() < end) {
    }
    while (Clock::now() < end) {
      const pid_t r = waitpid(pid_, &status_, WNOHANG);
      if (r == pid_) {
        exited_ = true;
        return true;
      }
      usleep(10000);
    }
    return false;
  }
  // the run's processes now: the launcher's children and the members of their process group
  std::vector<Proc> tree() const {
    std::vector<Proc> procs = all_procs(), out;
    std::set<pid_t> groups;
    for (const Proc& p : procs) {
      if (p.ppid == pid_ && alive(p)) groups.insert(p.pgrp);
    }
    for (const Proc& p : procs) {
      if (alive(p) && (p.ppid == pid_ || groups.count(p.pgrp))) out.push_back(p);
    }
    return out;
  }
  // the first of tree() whose argv[0] ends with program (and holds arg, if given)
  std::optional<Proc> find(const std::string& program, const std::string& arg = "") const {
    for (const Proc& p : tree()) {
      if (p.argv.empty() || p.argv[0].size() < program.size() ||
          p.argv[0].compare(p.argv[0].size() - program.size(), program.size(), program) != 0)
        continue;
      if (arg.empty() || std::find(p.argv.begin(), p.argv.end(), arg) != p.argv.end()) return p;
    }
    return std::nullopt;
  }

 private:
  // waits up to 100 ms for output; false at its end
  bool read_some() {
    pollfd p{fd_, POLLIN, 0};
    if (::poll(&p, 1, 100) <= 0) return true;
    char buf[65536];
    const ssize_t n = read(fd_, buf, sizeof(buf));
    if (n > 0) output_.append(buf, static_cast<size_t>(n));
    return n > 0 || (n < 0 && errno == EINTR);
  }

  std::string dir_;
  pid_t pid_ = -1;
  int fd_ = -1;
  bool exited_ = false;
  int status_ = 0;
  std::string output_;
  double seen_s_ = -1.0;
};

// no process of the run left: the snapshot's processes end (bounded poll), and none anywhere names
// the run directory on its command line
void expect_no_orphan(const std::vector<Proc>& snapshot, const std::string& dir) {
  const auto end = Clock::now() + std::chrono::duration<double>(30.0);
  auto survivors = [&] {
    std::vector<Proc> left;
    for (const Proc& p : snapshot) {
      const auto now = read_proc(p.pid);
      if (now && alive(*now) && now->argv == p.argv) left.push_back(*now);
    }
    for (const Proc& p : all_procs()) {
      if (!alive(p)) continue;
      for (const std::string& a : p.argv) {
        if (a.find(dir) != std::string::npos) left.push_back(p);
      }
    }
    return left;
  };
  std::vector<Proc> left = survivors();
  while (!left.empty() && Clock::now() < end) {
    usleep(20000);
    left = survivors();
  }
  for (const Proc& p : left) ADD_FAILURE() << "orphan: pid " << p.pid << " " << p.argv[0];
}

// every line of events.jsonl is a JSON object (a last line cut by the kill may lack its newline:
// record_file.hpp), and it holds the events of the run up to the kill
Json events_of(const std::string& dir) {
  const std::string text = read_file(dir + "/events.jsonl");
  Json events = Json::array();
  size_t at = 0;
  for (size_t nl; (nl = text.find('\n', at)) != std::string::npos; at = nl + 1) {
    const Json e = Json::parse(text.substr(at, nl - at), nullptr, false);
    EXPECT_TRUE(e.is_object()) << "events.jsonl line: " << text.substr(at, nl - at);
    events.push_back(e);
  }
  EXPECT_LE(text.size() - at, 4096u) << "more than the last write is unterminated";
  return events;
}
int count_events(const Json& events, const std::string& kind) {
  return static_cast<int>(std::count_if(
      events.begin(), events.end(), [&](const Json& e) { return e.value("event", "") == kind; }));
}

// the newest stamp of a tlog whose records are all whole frames (an incomplete last record is the
// kill's residue); -1 for none
double last_tlog_stamp_s(const std::string& path) {
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
