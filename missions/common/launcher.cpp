#include "uavsim/launch/launcher.hpp"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/statvfs.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <optional>
#include <regex>
#include <sstream>

#include "uavsim/common/angles.hpp"
#include "uavsim/common/frames.hpp"
#include "uavsim/common/record_file.hpp"

extern char** environ;

namespace uavsim::launch {

namespace {

using client::Error;
using client::Failure;
using SteadyClock = std::chrono::steady_clock;

constexpr double kProgramStop_s = 5.0;          // SIGTERM to SIGKILL for the mission programs
constexpr std::size_t kMaxLineBytes = 1 << 20;  // a child's longer "line" is cut there

// A child process with stdout and stderr on one pipe, read line by line without blocking.
struct Child {
  std::string name;
  pid_t pid = -1;
  int fd = -1;
  std::string buf;
  bool exited = false;
  int status = 0;

  bool stopped = false;   // stop() sent it a signal: its end is an ordinary one
  bool reported = false;  // its end was said and given to on_exit

  // Starts args with stdout and stderr on a pipe, stdin /dev/null, no other descriptor of the
  // launcher's, in process group *group (a new
  // one, whose id goes to *group, when it is 0 or its members are all gone), and with SIGKILL as
  // its parent-death signal. fork + exec rather than posix_spawn for the prctl; the child runs only
  // async-signal-safe calls until exec.
  Result<void> spawn(const std::vector<std::string>& args,
                     const std::vector<std::string>& env_extra, pid_t* group) {
    if (args.empty()) return Failure{Error::kInvalidArgument, name + ": no program"};
    std::vector<std::string> env;
    for (char** e = environ; *e != nullptr; ++e) {
      if (std::strncmp(*e, "UAVSIM_LOCKSTEP=", 16) != 0) env.emplace_back(*e);
    }
    env.insert(env.end(), env_extra.begin(), env_extra.end());
    std::vector<std::string> a = args;
    std::vector<char*> argv, envp;
    for (auto& s : a) argv.push_back(s.data());
    argv.push_back(nullptr);
    for (auto& s : env) envp.push_back(s.data());
    envp.push_back(nullptr);
    int fds[2], errfds[2];
    if (pipe2(fds, O_CLOEXEC) != 0) {
      return Failure{Error::kIo, name + ": pipe: " + std::strerror(errno)};
    }
    // the exec's failure comes back on errfds (closed by a successful exec)
    if (pipe2(errfds, O_CLOEXEC) != 0) {
      close(fds[0]);
      close(fds[1]);
      return Failure{Error::kIo, name + ": pipe: " + std::strerror(errno)};
    }
    const int devnull = open("/dev/null", O_RDONLY | O_CLOEXEC);
    const pid_t parent = getpid();
    const pid_t want_group = *group;
    pid = fork();
    if (pid == 0) {
      if (setpgid(0, want_group) != 0) (void)setpgid(0, 0);
      // die with the launcher; if it died before this line, the parent is already someone else
      if (prctl(PR_SET_PDEATHSIG, SIGKILL) != 0 || getppid() != parent) _exit(127);
      if (devnull >= 0) dup2(devnull, 0);
      dup2(fds[1], 1);
      dup2(fds[1], 2);
      // nothing else of the launcher's (its API socket, a caller's pipes): a program must not keep
      // them open after the launcher is gone; errfds[1] closes itself at exec
      if (errfds[1] > 3) (void)close_range(3, static_cast<unsigned>(errfds[1]) - 1, 0);
      (void)close_range(static_cast<unsigned>(errfds[1]) + 1, ~0U, 0);
      execve(argv[0], argv.data(), envp.data());
      const int err = errno;
      (void)!::write(errfds[1], &err, sizeof(err));
      _exit(127);
    }
    const int fork_errno = errno;
    if (devnull >= 0) close(devnull);
    close(fds[1]);
    close(errfds[1]);
    if (pid < 0) {
      close(fds[0]);
      close(errfds[0]);
      pid = -1;
      exited = true;
      return Failure{Error::kIo,
                     "cannot start " + args[0] + ": fork: " + std::strerror(fork_errno)};
    }
    // the same group from this side too, so that it holds before either side runs on
    if (setpgid(pid, want_group) != 0) (void)setpgid(pid, pid);
    int exec_errno = 0;
    ssize_t n;
    while ((n = read(errfds[0], &exec_errno, sizeof(exec_errno))) < 0 && errno == EINTR) {
    }
    close(errfds[0]);
    if (n == static_cast<ssize_t>(sizeof(exec_errno))) {
      close(fds[0]);
      waitpid(pid, &status, 0);
      pid = -1;
      exited = true;
      reported = true;
      return Failure{Error::kIo, "cannot start " + args[0] + ": " + std::strerror(exec_errno)};
    }
    if (const pid_t g = getpgid(pid); g > 0) *group = g;
    fd = fds[0];
    fcntl(fd, F_SETFL, O_NONBLOCK);
    return client::ok();
  }
  // reads what is there; complete lines out (the last, unterminated one when the output ends)
  std::vector<std::string> read_lines() {
    std::vector<std::string> lines;
    if (fd >= 0) {
      char tmp[8192];
      for (;;) {
        const ssize_t n = read(fd, tmp, sizeof(tmp));
        if (n > 0) {
          buf.append(tmp, static_cast<size_t>(n));
          continue;
        }
        if (n < 0 && errno == EINTR) continue;
        if (n == 0 || (errno != EAGAIN && errno != EWOULDBLOCK)) {  // end of output
          close(fd);
          fd = -1;
          if (!buf.empty() && buf.back() != '\n') buf += '\n';
        }
        break;
      }
    }
    size_t nl;
    while ((nl = buf.find('\n')) != std::string::npos) {
      lines.push_back(buf.substr(0, nl));
      buf.erase(0, nl + 1);
    }
    if (buf.size() > kMaxLineBytes) {
      lines.push_back(buf);
      buf.clear();
    }
    return lines;
  }
  bool reap() {
    if (pid <= 0 || exited) return exited || pid <= 0;
    if (waitpid(pid, &status, WNOHANG) == pid) exited = true;
    return exited;
  }
  void stop(int sig, double wall_timeout_s) {
    if (pid <= 0 || reap()) return;
    stopped = true;
    kill(pid, sig);
    const auto end = SteadyClock::now() + std::chrono::duration_cast<SteadyClock::duration>(
                                              std::chrono::duration<double>(wall_timeout_s));
    while (!reap() && SteadyClock::now() < end) usleep(10000);
    if (!exited) {
      kill(pid, SIGKILL);
      // a second Ctrl-C (catch_interrupts: no SA_RESTART) must not leave it unreaped
      while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
      }
      exited = true;
    }
  }
};

// "SIGKILL"; "signal N" for one without a name
std::string signal_name(int sig) {
  const char* abbrev = sigabbrev_np(sig);
  return abbrev != nullptr ? std::string("SIG") + abbrev : "signal " + std::to_string(sig);
}

// The OOM killer's count of kills in this process's memory cgroup (children inherit it): cgroup
// v2's memory.events or v1's memory.oom_control, at the cgroup's path or at the mount's root (a
// container sees its own cgroup there); nullopt when neither can be read.
std::optional<std::uint64_t> oom_kills() {
  std::vector<std::string> files;
  std::ifstream cg("/proc/self/cgroup");
  for (std::string line; std::getline(cg, line);) {
    const size_t a = line.find(':'), b = line.find(':', a + 1);
    if (a == std::string::npos || b == std::string::npos) continue;
    const std::string controllers = line.substr(a + 1, b - a - 1), path = line.substr(b + 1);
    if (controllers.empty()) {
      files.push_back("/sys/fs/cgroup" + path + "/memory.events");
      files.push_back("/sys/fs/cgroup/memory.events");
    } else if (controllers == "memory" || controllers.find("memory,") == 0 ||
               controllers.find(",memory") != std::string::npos) {
      files.push_back("/sys/fs/cgroup/memory" + path + "/memory.oom_control");
      files.push_back("/sys/fs/cgroup/memory/memory.oom_control");
    }
  }
  for (const std::string& f : files) {
    std::ifstream in(f);
    for (std::string key; in >> key;) {
      std::uint64_t n = 0;
      if (!(in >> n)) break;
      if (key == "oom_kill") return n;
    }
  }
  return std::nullopt;
}

// Whether the kernel's log (/dev/kmsg, readable by root) says the OOM killer killed pid.
bool kernel_log_names_oom_kill(pid_t pid) {
  const int fd = open("/dev/kmsg", O_RDONLY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) return false;
  const std::string killed = "Killed process " + std::to_string(pid) + " ";
  const std::string task = ",pid=" + std::to_string(pid) + ",";
  bool found = false;
  char record[8192];
  // one record per read, oldest first, until EAGAIN (the end); bounded against a flooding log
  for (int k = 0; k < 100000 && !found; ++k) {
    const ssize_t n = read(fd, record, sizeof(record) - 1);
    if (n < 0 && errno == EPIPE) continue;  // records overwritten while reading: go on
    if (n <= 0) break;
    const std::string_view r(record, static_cast<size_t>(n));
    found =
        r.find(killed) != std::string_view::npos ||
        (r.find("oom-kill:") != std::string_view::npos && r.find(task) != std::string_view::npos);
  }
  close(fd);
  return found;
}

// the signal that interrupted the run (catch_interrupts); 0 for none. A process-wide flag because
// a signal handler can reach nothing else.
volatile std::sig_atomic_t g_interrupt_signal = 0;
extern "C" void on_interrupt(int sig) {
  if (g_interrupt_signal == 0) g_interrupt_signal = sig;
}

std::string sim_time_text(double t_s) {
  if (t_s < 0) return "before the sim clock ran";
  char buf[48];
  std::snprintf(buf, sizeof(buf), "at sim t=%.2f s", t_s);
  return buf;
}

}  // namespace

nlohmann::json ProgramEnd::to_json() const {
  // no pid or process group: a summary is the same for the same seed, whatever the machine numbered
  // the processes (the launcher's own lines name the pids)
  nlohmann::json j = {{"name", name},
                      {"how", how},
                      {"abnormal", abnormal()},
                      {"stopped_by_launcher", stopped},
                      {"sim_time_s", sim_time_s}};
  if (!abnormal()) {
    // an expected end's sim time is when the launcher noticed it, after the run's pinned end: it
    // depends on the machine's load, and a summary is the same for the same seed
    j.erase("sim_time_s");
    std::string how_s = how;
    const std::string at = " " + sim_time_text(sim_time_s);
    if (const auto pos = how_s.find(at); pos != std::string::npos) how_s.erase(pos, at.size());
    j["how"] = how_s;
  }
  j["exit_code"] = exit_code ? nlohmann::json(*exit_code) : nlohmann::json();
  j["signal"] = signal ? nlohmann::json(signal_name(*signal)) : nlohmann::json();
  if (out_of_memory) j["out_of_memory"] = true;
  return j;
}

void catch_interrupts() {
  struct sigaction sa {};
  sa.sa_handler = on_interrupt;
  sigemptyset(&sa.sa_mask);
  // no SA_RESTART: a wait in poll() or a read ends at once with EINTR and the loop looks again
  sa.sa_flags = 0;
  (void)sigaction(SIGINT, &sa, nullptr);
  (void)sigaction(SIGTERM, &sa, nullptr);
}

int interrupted() { return g_interrupt_signal; }

int run_exit_code(bool harness_failed, bool success) {
  if (interrupted() != 0) return kExitInterrupted;
  if (harness_failed) return kExitHarness;
  return success ? kExitSuccess : kExitFellShort;
}

std::string sibling_program(const std::string& name) {
  char self[4096];
  const ssize_t n = readlink("/proc/self/exe", self, sizeof(self) - 1);
  std::string dir = n > 0 ? std::string(self, static_cast<size_t>(n)) : std::string();
  const size_t slash = dir.rfind('/');
  dir = slash == std::string::npos ? "." : dir.substr(0, slash);
  return dir + "/" + name;
}

// The ground-truth sampler of record_truth: its own lockstep connection, one CSV per vehicle. Each
// tick's rows reach each file in one write(2) (common::RecordFile), so a launcher killed at any
// moment leaves every tick's rows up to its last, whole.
struct TruthLog {
  struct Csv {
    common::RecordFile file;
    std::string rows;  // this tick's
  };
  std::string dir;
  double period_s = 0.1;
  std::unique_ptr<client::SimConnection> conn;
  std::map<std::string, Csv> files;
  std::uint64_t rows = 0;
  double time_s = -1.0;  // the sim time of the last tick's rows
  bool failed = false;
  bool trucks = true;       // ask for the truck until the world turns out to have none
  std::string write_error;  // the first file that could not be written, said once

  // the file of key (made with its header the first time)
  Csv* csv(const std::string& key, const std::string& file_name, const char* header) {
    Csv& c = files[key];
    if (!c.file.is_open() && c.file.error().empty()) {
      std::string why;
      if (!c.file.open(dir + "/" + file_name, &why) || !c.file.write(header)) {
        if (write_error.empty()) write_error = why.empty() ? c.file.error() : why;
        return nullptr;
      }
    }
    return &c;
  }
  // the tick's rows out, one write per file
  void write_rows() {
    for (auto& [key, c] : files) {
      if (c.rows.empty()) continue;
      if (!c.file.write(c.rows) && write_error.empty()) write_error = c.file.error();
      c.rows.clear();
    }
  }

  // the tick's rows, then done; alone on the lockstep (the mission's programs have left), it leaves
  // too, so that a pause armed for an empty lockstep (pause_at lockstep_empty) falls at this tick
  void on_tick(int64_t tick) {
    if (const auto st = conn->status(); !st || st->value("lockstep_clients", 0) <= 1) {
      (void)conn->lockstep_leave();
      failed = true;  // done: no more ticks
      return;
    }
    const auto r = conn->request({{"op", "vehicles"}});
    if (r) {
      const double t = r->value("time_s", 0.0);
      time_s = t;
      for (const auto& v : r->value("vehicles", nlohmann::json::array())) {
        const std::string name = v.value("name", "vehicle" + std::to_string(v.value("index", 0)));
        Csv* f = csv(name, "truth_" + name + ".csv",
                     "t_s,x_m,y_m,z_m,vx_m_s,vy_m_s,vz_m_s,roll_deg,pitch_deg,yaw_deg,battery_v,"
                     "battery_used_mah,mode,armed,crashed,on_ground\n");
        const auto p = v.value("position_enu_m", std::vector<double>{0, 0, 0});
        const auto vel = v.value("velocity_enu_m_s", std::vector<double>{0, 0, 0});
        const auto q = v.value("q_enu_body", std::vector<double>{1, 0, 0, 0});  // w x y z
        if (f == nullptr || p.size() < 3 || vel.size() < 3 || q.size() < 4) continue;
        // ZYX Euler angles of q_enu_body (yaw from east, counter-clockwise)
        const common::frames::Euler e =
            common::frames::euler_from_q_enu_flu(Eigen::Quaterniond(q[0], q[1], q[2], q[3]));
        const double roll = e.roll_rad * common::kRadToDeg;
        const double pitch = e.pitch_rad * common::kRadToDeg;
        const double yaw = e.yaw_rad * common::kRadToDeg;
        char line[512];
        std::snprintf(line, sizeof(line),
                      "%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%.2f,%.2f,%.2f,%.3f,%.1f,%s,%d,%d,%d\n",
                      t, p[0], p[1], p[2], vel[0], vel[1], vel[2], roll, pitch, yaw,
                      v.value("battery_v", 0.0), v.value("battery_used_mah", 0.0),
                      v.value("mode", std::string("?")).c_str(), v.value("armed", false) ? 1 : 0,
                      v.value("crashed", false) ? 1 : 0, v.value("on_ground", false) ? 1 : 0);
        f->rows += line;
        ++rows;
      }
    }
    // the truck (MBZIRC 2017), while the world has one
    if (trucks) {
      const auto tr = conn->request({{"op", "truck"}});
      if (!tr) {
        trucks = false;  // not_available: no truck in this world
      } else {
        const double t = tr->value("time_s", 0.0);
        for (const auto& k : tr->value("trucks", nlohmann::json::array())) {
          const std::string name = k.value("name", std::string("truck"));
          Csv* f = csv("truck:" + name, "truck_" + name + ".csv",
                       "t_s,x_m,y_m,z_m,vx_m_s,vy_m_s,vz_m_s,yaw_deg\n");
          const auto p = k.value("position_enu_m", std::vector<double>{0, 0, 0});
          const auto vel = k.value("velocity_enu_m_s", std::vector<double>{0, 0, 0});
          if (f == nullptr || p.size() < 3 || vel.size() < 3) continue;
          char line[256];
          std::snprintf(line, sizeof(line), "%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%.2f\n", t, p[0],
                        p[1], p[2], vel[0], vel[1], vel[2],
                        k.value("yaw_rad", 0.0) * 180.0 / common::kPi);
          f->rows += line;
        }
      }
    }
    write_rows();
    if (!conn->done(tick)) failed = true;
  }
  // answers every tick that has arrived
  void serve() {
    if (!conn || failed) return;
    if (!conn->poll(0)) {
      failed = true;
      return;
    }
    for (const client::SimMessage& msg : conn->take_messages()) {
      if (msg.kind() == "tick") on_tick(msg.json.value("tick", int64_t{0}));
    }
  }
};

struct Launcher::Impl {
  std::string name;
  bool quiet = false;
  SteadyClock::time_point start = SteadyClock::now();
  std::vector<std::unique_ptr<Child>> children;  // [0]: the server, once started
  Child* server = nullptr;
  std::unique_ptr<client::SimConnection> api;
  int api_port = 0;
  std::map<std::string, int> mavlink_ports;
  std::vector<std::function<void(const std::string&, const std::string&)>> line_callbacks;
  std::optional<std::pair<std::string, double>> truth_request;  // record_truth's dir and rate
  TruthLog truth;
  bool truth_error_said = false;
  pid_t group = 0;           // the children's process group; 0 before the first
  double sim_time_s = -1.0;  // the last known
  std::vector<std::function<void(const ProgramEnd&)>> exit_callbacks;
  std::vector<ProgramEnd> ends;                               // in the order they were noticed
  std::optional<std::uint64_t> oom_kills_seen = oom_kills();  // the cgroup's count so far
  std::string summary_path;                                   // keep_summary's
  nlohmann::json summary = nlohmann::json::object();
  double next_summary_s = 0.0;
  bool summary_error_said = false;
  // the interruption, once noticed: how many ends were noticed before it, and the sim time then
  std::optional<std::size_t> ends_before_interrupt;
  double interrupt_sim_time_s = -1.0;
  // the first run record that could not be written (the launcher's ground truth, the server's event
  // log, a tlog or the video as it says, a program's vision log as it says), with the sim time
  // then: records_error()
  std::string records_error;

  void note_records_error(const std::string& why) {
    if (!records_error.empty()) return;
    records_error = why + " " + sim_time_text(sim_time_s);
  }

  void say(const std::string& line) const {
    if (quiet) return;
    std::printf("%s\n", line.c_str());
    std::fflush(stdout);
  }
  void read_child(Child& c) {
    // the server says once when one of its records cannot be written on (a full disk): its event
    // log, a tlog or the video; a mission program the same of its vision log
    static const std::regex server_log_stops(
        R"(uavsim-server: the (event log|tlog|video) stops here: (.*))");
    static const std::regex vision_log_stops(R"(: the (vision log) stops here: (.*))");
    for (const std::string& l : c.read_lines()) {
      say("[" + c.name + "] " + l);
      std::smatch m;
      if (std::regex_search(l, m, &c == server ? server_log_stops : vision_log_stops)) {
        note_records_error(m[2].str());
      }
      for (auto& cb : line_callbacks) cb(c.name, l);
    }
  }
  void read_children() {
    for (auto& c : children) read_child(*c);
  }

  // how c (reaped) ended
  ProgramEnd end_of(const Child& c) {
    ProgramEnd e;
    e.name = c.name;
    e.pid = c.pid;
    e.stopped = c.stopped;
    e.sim_time_s = sim_time_s;
    std::string how;
    if (WIFSIGNALED(c.status)) {
      e.signal = WTERMSIG(c.status);
      how = "killed by " + signal_name(*e.signal);
      if (*e.signal == SIGKILL && !c.stopped) {
        // the OOM killer: its count in the cgroup went up, or the kernel's log names the pid
        const auto now = oom_kills();
        if (now && oom_kills_seen && *now > *oom_kills_seen) {
          e.out_of_memory = true;
          *oom_kills_seen += 1;  // this kill is this program's
        }
        if (!e.out_of_memory) e.out_of_memory = kernel_log_names_oom_kill(c.pid);
        if (e.out_of_memory) how += " \u2014 out of memory?";
      }
      if (WCOREDUMP(c.status)) how += " (core dumped)";
    } else {
      e.exit_code = WIFEXITED(c.status) ? WEXITSTATUS(c.status) : -1;
      how = *e.exit_code == 0 ? "exited normally"
                              : "exited with code " + std::to_string(*e.exit_code);
    }
    how += " " + sim_time_text(sim_time_s);
    e.how = c.stopped ? "stopped by the launcher (" + how + ")" : how;
    return e;
  }

  // the summary so far: partial, the programs, the first abnormal end
  nlohmann::json summary_with_programs(nlohmann::json j, bool complete, double wall_s) const {
    nlohmann::json programs = nlohmann::json::array();
    for (const auto& c : children) {
      if (c->pid <= 0 && c->reported && !c->exited) continue;
      const auto e = std::find_if(ends.begin(), ends.end(),
                                  [&](const ProgramEnd& x) { return x.pid == c->pid; });
      programs.push_back(e != ends.end() ? e->to_json()
                                         : nlohmann::json{{"name", c->name}, {"running", true}});
    }
    j["programs"] = std::move(programs);
    // the cause: among the ends before an interruption, a program killed by a signal rather than
    // those that exited because of it (agents end with a code when the server dies, and may be
    // noticed first), else the first abnormal end; then the interruption; then any abnormal end
    const auto before =
        ends.begin() + static_cast<std::ptrdiff_t>(ends_before_interrupt.value_or(ends.size()));
    auto cause = std::find_if(ends.begin(), before,
                              [](const ProgramEnd& e) { return e.abnormal() && e.signal; });
    if (cause == before) {
      cause = std::find_if(ends.begin(), before, [](const ProgramEnd& e) { return e.abnormal(); });
    }
    if (cause != before) {
      j["cause"] = cause->name + " " + cause->how;
    } else if (!records_error.empty()) {
      j["cause"] = "the run's records cannot be written: " + records_error;
    } else if (ends_before_interrupt) {
      j["cause"] = "the launcher was interrupted by " + signal_name(interrupted()) + " " +
                   sim_time_text(interrupt_sim_time_s);
    } else {
      cause =
          std::find_if(ends.begin(), ends.end(), [](const ProgramEnd& e) { return e.abnormal(); });
      j["cause"] =
          cause == ends.end() ? nlohmann::json() : nlohmann::json(cause->name + " " + cause->how);
    }
    j["interrupted"] = ends_before_interrupt.has_value();
    j["records_error"] = records_error.empty() ? nlohmann::json() : nlohmann::json(records_error);
    if (!j.contains("sim_time_s") || !complete) j["sim_time_s"] = sim_time_s;
    if (!j.contains("wall_time_s") || !complete) j["wall_time_s"] = wall_s;
    j["complete"] = complete;
    return j;
  }

  bool write_summary_file(const std::string& path, const nlohmann::json& j) {
    std::string why;
    if (common::replace_file_atomically(path, j.dump(2) + "\n", &why)) return true;
    if (!summary_error_said) {
      summary_error_said = true;
      std::fprintf(stderr, "%s: the run summary: %s\n", name.c_str(), why.c_str());
    }
    return false;
  }

  void rewrite_summary(double wall_s) {
    if (summary_path.empty()) return;
    (void)write_summary_file(summary_path, summary_with_programs(summary, false, wall_s));
  }
};

Launcher::Launcher(std::string name, bool quiet) : impl_(std::make_unique<Impl>()) {
  impl_->name = std::move(name);
  impl_->quiet = quiet;
}

Launcher::~Launcher() {
  // the callbacks may hold what the owner has destroyed by now
  impl_->exit_callbacks.clear();
  impl_->line_callbacks.clear();
  stop_all(kProgramStop_s);
}

void Launcher::check_children() {
  Impl& m = *impl_;
  if (interrupted() != 0 && !m.ends_before_interrupt) {
    // said once (on stderr, quiet or not, as an abnormal end), and recorded before the ends that
    // stopping the programs brings
    m.ends_before_interrupt = m.ends.size();
    m.interrupt_sim_time_s = m.sim_time_s;
    std::fprintf(stderr, "%s: interrupted by %s %s: stopping the run\n", m.name.c_str(),
                 signal_name(interrupted()).c_str(), sim_time_text(m.sim_time_s).c_str());
    std::fflush(stderr);
    m.rewrite_summary(wall_s());
  }
  for (auto& c : m.children) {
    if (c->reported || c->pid <= 0 || !c->reap()) continue;
    c->reported = true;
    m.read_child(*c);  // its last words before its end
    const ProgramEnd e = m.end_of(*c);
    m.ends.push_back(e);
    const std::string line =
        m.name + ": " + e.name + " (pid " + std::to_string(e.pid) + ") " + e.how;
    if (e.abnormal()) {
      std::fprintf(stderr, "%s\n", line.c_str());
      std::fflush(stderr);
    } else {
      m.say(line);
    }
    for (auto& cb : m.exit_callbacks) cb(e);
    m.rewrite_summary(wall_s());
  }
  if (!m.truth.write_error.empty() && !m.truth_error_said) {
    m.truth_error_said = true;
    m.note_records_error(m.truth.write_error);
    std::fprintf(stderr, "%s: the ground truth stops here: %s\n", m.name.c_str(),
                 m.truth.write_error.c_str());
  }
}

pid_t Launcher::process_group() const { return impl_->group; }

void Launcher::note_sim_time(double t_s) {
  Impl& m = *impl_;
  if (!std::isfinite(t_s)) return;
  m.sim_time_s = t_s;
  if (!m.summary_path.empty() && t_s >= m.next_summary_s) {
    m.next_summary_s = (std::floor(t_s / kSummaryPeriod_s) + 1.0) * kSummaryPeriod_s;
    m.rewrite_summary(wall_s());
  }
}

void Launcher::on_exit(std::function<void(const ProgramEnd&)> cb) {
  impl_->exit_callbacks.push_back(std::move(cb));
}

std::optional<ProgramEnd> Launcher::ended(const std::string& name) const {
  for (const ProgramEnd& e : impl_->ends) {
    if (e.name == name) return e;
  }
  return std::nullopt;
}

const std::string& Launcher::records_error() const { return impl_->records_error; }

std::string Launcher::server_end() const {
  const auto e = ended("server");
  return e ? "the server (pid " + std::to_string(e->pid) + ") " + e->how : "the server exited";
}

void Launcher::keep_summary(const std::string& path, nlohmann::json partial) {
  Impl& m = *impl_;
  m.summary_path = path;
  m.summary = partial.is_object() ? std::move(partial) : nlohmann::json::object();
  m.next_summary_s = std::max(0.0, m.sim_time_s) + kSummaryPeriod_s;
  m.rewrite_summary(wall_s());  // a run killed before its first period still has one
}

void Launcher::update_summary(const nlohmann::json& fields) {
  if (fields.is_object()) impl_->summary.update(fields);
}

bool Launcher::write_summary(const std::string& path, nlohmann::json summary) {
  Impl& m = *impl_;
  check_children();
  if (m.summary_path == path) m.summary_path.clear();  // no partial over the final one
  return m.write_summary_file(path, m.summary_with_programs(std::move(summary), true, wall_s()));
}

Result<void> Launcher::start_server(const ServerSpec& spec) {
  Impl& m = *impl_;
  if (m.server != nullptr) return Failure{Error::kInvalidArgument, "the server is already started"};
  auto& c = m.children.emplace_back(std::make_unique<Child>());
  c->name = "server";
  m.server = c.get();
  std::vector<std::string> args{
      spec.path, spec.world,           "--rate", "0", "--mavlink-port", "0", "--api-port",
      "0",       "--lockstep-timeout", "120"};
  args.insert(args.end(), spec.extra_args.begin(), spec.extra_args.end());
  if (auto r = c->spawn(args, {}, &m.group); !r) return r;

  // the banner: "uavsim-server: uav0: MAVLink on tcp:127.0.0.1:PORT", ..., then the API's port
  static const std::regex mav_re(R"(uavsim-server: (\S+): MAVLink on tcp:[0-9.]+:(\d+))");
  static const std::regex api_re(R"(sim API on tcp:[0-9.]+:(\d+))");
  while (m.api_port == 0 && wall_s() < spec.start_timeout_s && interrupted() == 0) {
    pollfd p{c->fd, POLLIN, 0};
    ::poll(&p, 1, 200);
    for (const std::string& l : c->read_lines()) {
      m.say("[server] " + l);
      for (auto& cb : m.line_callbacks) cb(c->name, l);
      std::smatch sm;
      if (std::regex_search(l, sm, mav_re)) {
        const long port = std::strtol(sm[2].str().c_str(), nullptr, 10);
        if (port > 0 && port <= 65535) m.mavlink_ports[sm[1]] = static_cast<int>(port);
      }
      if (std::regex_search(l, sm, api_re)) {
        const long port = std::strtol(sm[1].str().c_str(), nullptr, 10);
        if (port > 0 && port <= 65535) m.api_port = static_cast<int>(port);
      }
    }
    if (c->fd < 0) break;
  }
  if (m.api_port == 0 && interrupted() != 0) {
    return Failure{Error::kCancelled, "interrupted by " + signal_name(interrupted())};
  }
  if (m.api_port == 0) {
    return Failure{Error::kTimeout, c->fd < 0 ? "the server exited before it served the API"
                                              : "the server printed no sim API port"};
  }
  auto api = client::SimConnection::connect("127.0.0.1", static_cast<uint16_t>(m.api_port),
                                            std::max(1.0, spec.start_timeout_s - wall_s()));
  if (!api) return Failure{api.code(), "cannot connect to the sim API: " + api.message()};
  m.api = std::move(*api);
  return client::ok();
}

client::SimConnection& Launcher::api() { return *impl_->api; }
int Launcher::api_port() const { return impl_->api_port; }
int Launcher::mavlink_port(const std::string& vehicle) const {
  const auto it = impl_->mavlink_ports.find(vehicle);
  return it == impl_->mavlink_ports.end() ? 0 : it->second;
}

Result<void> Launcher::spawn(const std::string& name, const std::vector<std::string>& argv,
                             const std::vector<std::string>& env) {
  auto& c = impl_->children.emplace_back(std::make_unique<Child>());
  c->name = name;
  return c->spawn(argv, env, &impl_->group);
}

std::string Launcher::lockstep_env(double period_s) const {
  char period[32];
  std::snprintf(period, sizeof(period), "%g", period_s);
  return "UAVSIM_LOCKSTEP=127.0.0.1:" + std::to_string(impl_->api_port) + "/" + period;
}

Result<void> Launcher::wait_lockstep_clients(int n, double timeout_s) {
  Impl& m = *impl_;
  if (!m.api) return Failure{Error::kNotConnected, "the server is not started"};
  const double end_s = wall_s() + timeout_s;
  for (;;) {
    const auto s = m.api->status();
    if (!s) return s.error();
    if (s->value("lockstep_clients", 0) >= n) {
      if (m.truth_request && !m.truth.conn) start_truth();
      return client::ok();
    }
    if (interrupted() != 0) {
      return Failure{Error::kCancelled, "interrupted by " + signal_name(interrupted())};
    }
    if (wall_s() > end_s) {
      return Failure{Error::kTimeout, std::to_string(s->value("lockstep_clients", 0)) + " of " +
                                          std::to_string(n) + " lockstep clients joined"};
    }
    m.read_children();
    check_children();
    usleep(20000);
  }
}

void Launcher::on_line(std::function<void(const std::string&, const std::string&)> cb) {
  impl_->line_callbacks.push_back(std::move(cb));
}

void Launcher::pump(int timeout_ms) {
  Impl& m = *impl_;
  std::vector<pollfd> fds;
  if (m.api && m.api->fd() >= 0) fds.push_back({m.api->fd(), POLLIN, 0});
  if (m.truth.conn && m.truth.conn->fd() >= 0) fds.push_back({m.truth.conn->fd(), POLLIN, 0});
  for (auto& c : m.children) {
    if (c->fd >= 0) fds.push_back({c->fd, POLLIN, 0});
  }
  if (!fds.empty()) {
    ::poll(fds.data(), fds.size(), std::max(0, timeout_ms));
  } else if (timeout_ms > 0) {
    usleep(static_cast<useconds_t>(timeout_ms) * 1000);
  }
  // the API first, then the programs' output: a program writes a line before it sends the lockstep
  // `done` that lets the clock reach the next tick, so once a tick has been read here every line
  // the programs wrote before it is in their pipes, and the reads below see it in the same pass.
  // (In the other order a line written between the two reads would meet a later tick: the fault
  // injector of the 2017 run then acted a tick late on a loaded machine, and two runs of one seed
  // diverged.)
  if (m.api) (void)m.api->poll(0);
  m.read_children();
  m.truth.serve();
  if (m.truth.time_s > m.sim_time_s) note_sim_time(m.truth.time_s);
  check_children();
}

void Launcher::record_truth(const std::string& dir, double rate_hz) {
  impl_->truth_request = std::make_pair(dir, rate_hz > 0 ? rate_hz : 10.0);
}

std::uint64_t Launcher::truth_rows() const { return impl_->truth.rows; }

void Launcher::start_truth() {
  Impl& m = *impl_;
  m.truth.dir = m.truth_request->first;
  m.truth.period_s = 1.0 / m.truth_request->second;
  auto conn = client::SimConnection::connect("127.0.0.1", static_cast<uint16_t>(m.api_port), 10.0);
  if (!conn) {
    m.say(m.name + ": no ground truth: " + conn.message());
    return;
  }
  m.truth.conn = std::move(*conn);
  if (auto j = m.truth.conn->lockstep_join(m.truth.period_s, 120.0); !j) {
    m.say(m.name + ": no ground truth: lockstep_join: " + j.message());
    m.truth.conn.reset();
  }
}

std::string default_run_dir(const std::string& mission, uint64_t seed) {
  const std::time_t now = std::time(nullptr);
  std::tm utc{};
  gmtime_r(&now, &utc);
  char stamp[32];
  std::strftime(stamp, sizeof(stamp), "%Y%m%d-%H%M%S", &utc);
  return "runs/" + mission + "-seed" + std::to_string(seed) + "-" + stamp;
}

bool make_run_dir(const std::string& dir, std::string* why) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec || !std::filesystem::is_directory(dir)) {
    if (why != nullptr) *why = "cannot make the run directory " + dir + ": " + ec.message();
    return false;
  }
  // a file can be made there (a read-only file system says so only now)...
  const std::string probe = dir + "/.uavsim-write-test-" + std::to_string(getpid());
  common::RecordFile f;
  std::string error;
  if (!f.open(probe, &error) || !f.write("x")) {
    if (why != nullptr) {
      *why =
          "cannot write in the run directory " + dir + ": " + (error.empty() ? f.error() : error);
    }
    f.close();
    std::remove(probe.c_str());
    return false;
  }
  f.close();
  std::remove(probe.c_str());
  // ...and the logs have room to start
  struct statvfs fs {};
  if (statvfs(dir.c_str(), &fs) == 0) {
    const auto free_bytes = static_cast<std::uint64_t>(fs.f_bavail) * fs.f_frsize;
    if (free_bytes < kMinRunDirFreeBytes) {
      if (why != nullptr) {
        *why = "the run directory " + dir + " has " + std::to_string(free_bytes / 1024) +
               " KiB free; a run needs at least " + std::to_string(kMinRunDirFreeBytes >> 10) +
               " KiB";
      }
      return false;
    }
  }
  return true;
}

Result<RunFiles> resolve_run_files(const std::string& mission, uint64_t seed,
                                   const std::string& run_dir_option, const std::string& video,
                                   const std::string& summary, bool record) {
  RunFiles f;
  if (run_dir_option.empty() || run_dir_option == "auto") {
    f.dir = default_run_dir(mission, seed);
  } else if (run_dir_option != "none") {
    f.dir = run_dir_option;
  }
  if (!f.dir.empty()) {
    std::string why;
    if (!make_run_dir(f.dir, &why)) return Failure{Error::kIo, why};
  }
  f.video = !record          ? std::string()
            : !video.empty() ? video
            : f.dir.empty()  ? ""
                             : f.dir + "/video.mp4";
  f.summary = !summary.empty() ? summary : f.dir.empty() ? "" : f.dir + "/summary.json";
  return f;
}

void Launcher::say(const std::string& line) const { impl_->say(line); }

double Launcher::wall_s() const {
  return std::chrono::duration<double>(SteadyClock::now() - impl_->start).count();
}

bool Launcher::programs_done(const std::string& except) {
  check_children();
  bool done = true;
  for (auto& c : impl_->children) {
    if (c.get() == impl_->server || (!except.empty() && c->name == except)) continue;
    done = c->reap() && c->fd < 0 && done;
  }
  return done;
}

bool Launcher::server_exited() {
  check_children();
  return impl_->server == nullptr || impl_->server->reap();
}

void Launcher::stop_all(double timeout_s) {
  Impl& m = *impl_;
  // the ground truth first: its lockstep membership gone (its rows are written tick by tick)
  m.truth.conn.reset();
  // the programs first (newest first), then the server
  for (size_t i = m.children.size(); i-- > 0;) {
    if (m.children[i].get() != m.server)
      m.children[i]->stop(SIGTERM, std::min(kProgramStop_s, timeout_s));
  }
  if (m.server != nullptr) m.server->stop(SIGTERM, timeout_s);
  m.read_children();
  check_children();
}

}  // namespace uavsim::launch
