#include "uavsim/launch/launcher.hpp"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <optional>
#include <regex>

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

  Result<void> spawn(const std::vector<std::string>& args,
                     const std::vector<std::string>& env_extra) {
    if (args.empty()) return Failure{Error::kInvalidArgument, name + ": no program"};
    int fds[2];
    if (pipe2(fds, O_CLOEXEC) != 0) {
      return Failure{Error::kIo, name + ": pipe: " + std::strerror(errno)};
    }
    posix_spawn_file_actions_t fa;
    posix_spawn_file_actions_init(&fa);
    posix_spawn_file_actions_adddup2(&fa, fds[1], 1);
    posix_spawn_file_actions_adddup2(&fa, fds[1], 2);
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
    const int rc = posix_spawn(&pid, argv[0], &fa, nullptr, argv.data(), envp.data());
    posix_spawn_file_actions_destroy(&fa);
    close(fds[1]);
    if (rc != 0) {
      close(fds[0]);
      pid = -1;
      exited = true;
      return Failure{Error::kIo, "cannot start " + args[0] + ": " + std::strerror(rc)};
    }
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
    kill(pid, sig);
    const auto end = SteadyClock::now() + std::chrono::duration_cast<SteadyClock::duration>(
                                              std::chrono::duration<double>(wall_timeout_s));
    while (!reap() && SteadyClock::now() < end) usleep(10000);
    if (!exited) {
      kill(pid, SIGKILL);
      waitpid(pid, &status, 0);
      exited = true;
    }
  }
};

}  // namespace

std::string sibling_program(const std::string& name) {
  char self[4096];
  const ssize_t n = readlink("/proc/self/exe", self, sizeof(self) - 1);
  std::string dir = n > 0 ? std::string(self, static_cast<size_t>(n)) : std::string();
  const size_t slash = dir.rfind('/');
  dir = slash == std::string::npos ? "." : dir.substr(0, slash);
  return dir + "/" + name;
}

// The ground-truth sampler of record_truth: its own lockstep connection, one CSV per vehicle.
struct TruthLog {
  std::string dir;
  double period_s = 0.1;
  std::unique_ptr<client::SimConnection> conn;
  std::map<std::string, std::unique_ptr<std::ofstream>> files;
  std::uint64_t rows = 0;
  bool failed = false;
  bool trucks = true;  // ask for the truck until the world turns out to have none

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
      for (const auto& v : r->value("vehicles", nlohmann::json::array())) {
        const std::string name = v.value("name", "vehicle" + std::to_string(v.value("index", 0)));
        auto& f = files[name];
        if (!f) {
          f = std::make_unique<std::ofstream>(dir + "/truth_" + name + ".csv");
          *f << "t_s,x_m,y_m,z_m,vx_m_s,vy_m_s,vz_m_s,roll_deg,pitch_deg,yaw_deg,battery_v,"
                "battery_used_mah,mode,armed,crashed,on_ground\n";
        }
        const auto p = v.value("position_enu_m", std::vector<double>{0, 0, 0});
        const auto vel = v.value("velocity_enu_m_s", std::vector<double>{0, 0, 0});
        const auto q = v.value("q_enu_body", std::vector<double>{1, 0, 0, 0});  // w x y z
        if (p.size() < 3 || vel.size() < 3 || q.size() < 4) continue;
        // ZYX Euler angles of q_enu_body (yaw from east, counter-clockwise)
        const double w = q[0], x = q[1], y = q[2], z = q[3];
        constexpr double kDeg = 180.0 / 3.14159265358979323846;
        const double roll = std::atan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y)) * kDeg;
        const double pitch = std::asin(std::clamp(2 * (w * y - z * x), -1.0, 1.0)) * kDeg;
        const double yaw = std::atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z)) * kDeg;
        char line[512];
        std::snprintf(line, sizeof(line), "%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%.2f,%.2f,%.2f,%.3f,%.1f,%s,%d,%d,%d\n",
                      t, p[0], p[1], p[2], vel[0], vel[1], vel[2], roll, pitch, yaw, v.value("battery_v", 0.0),
                      v.value("battery_used_mah", 0.0), v.value("mode", std::string("?")).c_str(),
                      v.value("armed", false) ? 1 : 0, v.value("crashed", false) ? 1 : 0,
                      v.value("on_ground", false) ? 1 : 0);
        *f << line;
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
          auto& f = files["truck:" + name];
          if (!f) {
            f = std::make_unique<std::ofstream>(dir + "/truck_" + name + ".csv");
            *f << "t_s,x_m,y_m,z_m,vx_m_s,vy_m_s,vz_m_s,yaw_deg\n";
          }
          const auto p = k.value("position_enu_m", std::vector<double>{0, 0, 0});
          const auto vel = k.value("velocity_enu_m_s", std::vector<double>{0, 0, 0});
          if (p.size() < 3 || vel.size() < 3) continue;
          char line[256];
          std::snprintf(line, sizeof(line), "%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%.2f\n", t, p[0], p[1], p[2], vel[0],
                        vel[1], vel[2], k.value("yaw_rad", 0.0) * 180.0 / 3.14159265358979323846);
          *f << line;
        }
      }
    }
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

  void say(const std::string& line) const {
    if (quiet) return;
    std::printf("%s\n", line.c_str());
    std::fflush(stdout);
  }
  void read_child(Child& c) {
    for (const std::string& l : c.read_lines()) {
      say("[" + c.name + "] " + l);
      for (auto& cb : line_callbacks) cb(c.name, l);
    }
  }
  void read_children() {
    for (auto& c : children) read_child(*c);
  }
};

Launcher::Launcher(std::string name, bool quiet) : impl_(std::make_unique<Impl>()) {
  impl_->name = std::move(name);
  impl_->quiet = quiet;
}

Launcher::~Launcher() { stop_all(kProgramStop_s); }

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
  if (auto r = c->spawn(args, {}); !r) return r;

  // the banner: "uavsim-server: uav0: MAVLink on tcp:127.0.0.1:PORT", ..., then the API's port
  static const std::regex mav_re(R"(uavsim-server: (\S+): MAVLink on tcp:[0-9.]+:(\d+))");
  static const std::regex api_re(R"(sim API on tcp:[0-9.]+:(\d+))");
  while (m.api_port == 0 && wall_s() < spec.start_timeout_s) {
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
  return c->spawn(argv, env);
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
    if (wall_s() > end_s) {
      return Failure{Error::kTimeout, std::to_string(s->value("lockstep_clients", 0)) + " of " +
                                          std::to_string(n) + " lockstep clients joined"};
    }
    m.read_children();
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
  m.read_children();
  if (m.api) (void)m.api->poll(0);
  m.truth.serve();
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
  f.video = !record ? std::string() : !video.empty() ? video : f.dir.empty() ? "" : f.dir + "/video.mp4";
  f.summary = !summary.empty() ? summary : f.dir.empty() ? "" : f.dir + "/summary.json";
  return f;
}

void Launcher::say(const std::string& line) const { impl_->say(line); }

double Launcher::wall_s() const {
  return std::chrono::duration<double>(SteadyClock::now() - impl_->start).count();
}

bool Launcher::programs_done(const std::string& except) {
  bool done = true;
  for (auto& c : impl_->children) {
    if (c.get() == impl_->server || (!except.empty() && c->name == except)) continue;
    done = c->reap() && c->fd < 0 && done;
  }
  return done;
}

bool Launcher::server_exited() { return impl_->server == nullptr || impl_->server->reap(); }

void Launcher::stop_all(double timeout_s) {
  Impl& m = *impl_;
  // the ground truth first: its files complete, its lockstep membership gone
  m.truth.conn.reset();
  for (auto& [name, f] : m.truth.files) f->flush();
  // the programs first (newest first), then the server
  for (size_t i = m.children.size(); i-- > 0;) {
    if (m.children[i].get() != m.server)
      m.children[i]->stop(SIGTERM, std::min(kProgramStop_s, timeout_s));
  }
  if (m.server != nullptr) m.server->stop(SIGTERM, timeout_s);
  m.read_children();
}

}  // namespace uavsim::launch
