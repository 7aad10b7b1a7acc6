// The chaos tests' view of a running launcher (coverage-run, mbzirc2017-run, mbzirc2020-run): the
// launcher as a child process whose output is read as it comes, the processes of its run (its
// children and their process group, from /proc), a check that none of them outlives the run, and
// the run directory's event log read back line by line. The waits are bounded polls whose bound
// only turns a hang into a failure; what they wait for is the run's own progress.
#pragma once

#include <gtest/gtest.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "../../support/piped_child.hpp"

namespace uavsim::tests {

using RunClock = std::chrono::steady_clock;

inline constexpr double kRunWallBound_s = 300.0;  // a hang, not a slow machine

inline std::string read_whole_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

// a process's argv, parent, group and state, from /proc
struct Proc {
  pid_t pid = 0;
  pid_t ppid = 0;
  pid_t pgrp = 0;
  char state = 0;
  std::vector<std::string> argv;
};
inline std::optional<Proc> read_proc(pid_t pid) {
  const std::string dir = "/proc/" + std::to_string(pid);
  const std::string stat = read_whole_file(dir + "/stat");
  const size_t paren = stat.rfind(')');
  if (paren == std::string::npos) return std::nullopt;
  Proc p;
  p.pid = pid;
  long ppid = 0, pgrp = 0;
  std::istringstream rest(stat.substr(paren + 2));
  rest >> p.state >> ppid >> pgrp;
  p.ppid = static_cast<pid_t>(ppid);
  p.pgrp = static_cast<pid_t>(pgrp);
  std::string cmd = read_whole_file(dir + "/cmdline");
  for (size_t a = 0; a < cmd.size();) {
    const size_t z = cmd.find('\0', a);
    p.argv.push_back(cmd.substr(a, z == std::string::npos ? std::string::npos : z - a));
    if (z == std::string::npos) break;
    a = z + 1;
  }
  return p;
}
inline std::vector<Proc> all_procs() {
  std::vector<Proc> out;
  for (const auto& e : std::filesystem::directory_iterator("/proc")) {
    const std::string n = e.path().filename();
    if (n.find_first_not_of("0123456789") != std::string::npos) continue;
    if (auto p = read_proc(static_cast<pid_t>(std::stol(n)))) out.push_back(*p);
  }
  return out;
}
inline bool alive(const Proc& p) { return p.state != 0 && p.state != 'Z' && p.state != 'X'; }

// A launcher (args[0] its path) as a child process, stdout and stderr on one pipe read as it comes.
// Killed (SIGKILL) and reaped at destruction if it still runs.
class RunProcess {
 public:
  // before_exec: as spawn_piped's (a limit for the launcher and all it starts)
  explicit RunProcess(std::vector<std::string> args,
                      const std::function<void()>& before_exec = {}) {
    pid_ = uavsim::testing::spawn_piped(std::move(args), &fd_, before_exec);
  }
  ~RunProcess() {
    if (pid_ > 0 && !exited_) {
      kill(pid_, SIGKILL);
      waitpid(pid_, &status_, 0);
    }
    if (fd_ >= 0) close(fd_);
  }
  RunProcess(const RunProcess&) = delete;
  RunProcess& operator=(const RunProcess&) = delete;

  pid_t pid() const { return pid_; }
  const std::string& output() const { return output_; }
  // the wait status once until_exit() returned true
  int status() const { return status_; }

  // reads output until done() (asked again after each read and every 100 ms) holds; false if the
  // launcher's output ended (or the bound passed) first
  bool until(const std::function<bool()>& done) {
    const auto end = RunClock::now() + std::chrono::duration<double>(kRunWallBound_s);
    while (RunClock::now() < end) {
      if (done()) return true;
      if (!read_some()) return done();
    }
    return false;
  }
  // reads all output until the launcher exits; false if it does not within the bound
  bool until_exit() {
    const auto end = RunClock::now() + std::chrono::duration<double>(kRunWallBound_s);
    while (read_some() && RunClock::now() < end) {
    }
    while (RunClock::now() < end) {
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

  pid_t pid_ = -1;
  int fd_ = -1;
  bool exited_ = false;
  int status_ = 0;
  std::string output_;
};

// no process of the run left: the snapshot's processes end (bounded poll), and none anywhere names
// the run directory on its command line
inline void expect_no_orphan(const std::vector<Proc>& snapshot, const std::string& dir) {
  const auto end = RunClock::now() + std::chrono::duration<double>(30.0);
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
  while (!left.empty() && RunClock::now() < end) {
    usleep(20000);
    left = survivors();
  }
  for (const Proc& p : left) ADD_FAILURE() << "orphan: pid " << p.pid << " " << p.argv[0];
}

// every line of the run directory's events.jsonl is a JSON object (a last line cut by a kill may
// lack its newline: record_file.hpp); its events in order
inline nlohmann::json events_of(const std::string& dir) {
  const std::string text = read_whole_file(dir + "/events.jsonl");
  nlohmann::json events = nlohmann::json::array();
  size_t at = 0;
  for (size_t nl; (nl = text.find('\n', at)) != std::string::npos; at = nl + 1) {
    const nlohmann::json e = nlohmann::json::parse(text.substr(at, nl - at), nullptr, false);
    EXPECT_TRUE(e.is_object()) << "events.jsonl line: " << text.substr(at, nl - at);
    events.push_back(e);
  }
  EXPECT_LE(text.size() - at, 4096u) << "more than the last write is unterminated";
  return events;
}

// the last ground-truth row's sim time in a run directory's truth_VEHICLE.csv (the launcher
// writes it tick by tick); -1 while it has none
inline double last_truth_time_s(const std::string& path) {
  const std::string text = read_whole_file(path);
  const size_t end = text.rfind('\n');
  if (end == std::string::npos || end == 0) return -1.0;
  const size_t begin = text.rfind('\n', end - 1);
  if (begin == std::string::npos) return -1.0;  // the header alone
  const std::string row = text.substr(begin + 1, end - begin - 1);
  char* after = nullptr;
  const double t_s = std::strtod(row.c_str(), &after);
  return after != row.c_str() && *after == ',' ? t_s : -1.0;
}

}  // namespace uavsim::tests
