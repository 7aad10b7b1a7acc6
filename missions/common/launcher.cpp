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
#include <cstdio>
#include <cstring>
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
    if (s->value("lockstep_clients", 0) >= n) return client::ok();
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
}

void Launcher::say(const std::string& line) const { impl_->say(line); }

double Launcher::wall_s() const {
  return std::chrono::duration<double>(SteadyClock::now() - impl_->start).count();
}

bool Launcher::programs_done() {
  bool done = true;
  for (auto& c : impl_->children) {
    if (c.get() == impl_->server) continue;
    done = c->reap() && c->fd < 0 && done;
  }
  return done;
}

bool Launcher::server_exited() { return impl_->server == nullptr || impl_->server->reap(); }

void Launcher::stop_all(double timeout_s) {
  Impl& m = *impl_;
  // the programs first (newest first), then the server
  for (size_t i = m.children.size(); i-- > 0;) {
    if (m.children[i].get() != m.server)
      m.children[i]->stop(SIGTERM, std::min(kProgramStop_s, timeout_s));
  }
  if (m.server != nullptr) m.server->stop(SIGTERM, timeout_s);
  m.read_children();
}

}  // namespace uavsim::launch
