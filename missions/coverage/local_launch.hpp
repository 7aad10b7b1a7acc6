// coverage-run's launch plumbing, kept in this one file until the shared launch library
// (missions/common, uavsim_launch) can replace it: a child process whose stdout and stderr are read
// line by line without blocking, and a line-JSON client of the sim API (requests wait for their
// reply by id; streamed messages are queued). Launcher-only code (not a mission's).
#pragma once

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstring>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

extern char** environ;

namespace uavsim::missions::coverage::launch {

using Json = nlohmann::json;
using WallClock = std::chrono::steady_clock;

// a program installed beside this one (found through /proc/self/exe)
inline std::string sibling(const std::string& name) {
  char self[4096];
  const ssize_t n = readlink("/proc/self/exe", self, sizeof(self) - 1);
  std::string dir = n > 0 ? std::string(self, static_cast<size_t>(n)) : std::string(".");
  const size_t slash = dir.rfind('/');
  dir = slash == std::string::npos ? "." : dir.substr(0, slash);
  return dir + "/" + name;
}

// A child process with stdout and stderr on one pipe, read line by line without blocking.
struct Child {
  std::string name;
  pid_t pid = -1;
  int fd = -1;
  std::string buf;
  bool exited = false;
  int status = 0;

  bool spawn(const std::vector<std::string>& args, const std::vector<std::string>& env_extra) {
    int fds[2];
    if (pipe2(fds, O_CLOEXEC) != 0) return false;
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
      return false;
    }
    fd = fds[0];
    fcntl(fd, F_SETFL, O_NONBLOCK);
    return true;
  }
  // what is there; complete lines out (the last partial line once the pipe closes)
  std::vector<std::string> read_lines() {
    std::vector<std::string> lines;
    if (fd >= 0) {
      char tmp[16384];
      for (;;) {
        const ssize_t n = read(fd, tmp, sizeof(tmp));
        if (n > 0) {
          buf.append(tmp, static_cast<size_t>(n));
          continue;
        }
        if (n == 0) {
          close(fd);
          fd = -1;
          if (!buf.empty()) buf += '\n';
        }
        break;
      }
    }
    size_t nl;
    while ((nl = buf.find('\n')) != std::string::npos) {
      lines.push_back(buf.substr(0, nl));
      buf.erase(0, nl + 1);
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
    const auto end = WallClock::now() + std::chrono::duration<double>(wall_timeout_s);
    while (!reap() && WallClock::now() < end) usleep(10000);
    if (!exited) {
      kill(pid, SIGKILL);
      waitpid(pid, &status, 0);
      exited = true;
    }
  }
};

// Line-JSON client of the sim API: request() waits for its reply (by id) and returns it whole;
// streamed messages ("event") read meanwhile are queued for take_messages().
class Api {
 public:
  Api() = default;
  Api(const Api&) = delete;
  Api& operator=(const Api&) = delete;
  ~Api() {
    if (fd_ >= 0) close(fd_);
  }
  bool connect(int port) {
    fd_ = socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_port = htons(static_cast<uint16_t>(port));
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    if (::connect(fd_, reinterpret_cast<sockaddr*>(&a), sizeof(a)) != 0) return false;
    return read_one(10.0).has_value();  // hello
  }
  int fd() const { return fd_; }
  // the reply's result, or nothing (with the reply or the reason in *error)
  std::optional<Json> request(Json j, std::string* error = nullptr, double wall_timeout_s = 60.0) {
    j["id"] = ++next_id_;
    const std::string line = j.dump() + "\n";
    if (send(fd_, line.data(), line.size(), MSG_NOSIGNAL) != static_cast<ssize_t>(line.size())) {
      if (error) *error = "cannot send to the sim API";
      return std::nullopt;
    }
    const auto end = WallClock::now() + std::chrono::duration<double>(wall_timeout_s);
    while (WallClock::now() < end) {
      auto m = read_one(std::chrono::duration<double>(end - WallClock::now()).count());
      if (!m) break;
      if (m->contains("event")) {
        queue_.push_back(std::move(*m));
        continue;
      }
      const Json id = m->value("id", Json());
      if (!id.is_number_integer() || id.get<int>() != next_id_) continue;
      if (m->value("ok", false)) return m->value("result", Json::object());
      if (error) *error = m->dump();
      return std::nullopt;
    }
    if (error) *error = "no reply from the sim API";
    return std::nullopt;
  }
  // Sends without waiting for the reply (it is skipped when it comes).
  bool send_only(Json j) {
    j["id"] = "nowait";
    const std::string line = j.dump() + "\n";
    return send(fd_, line.data(), line.size(), MSG_NOSIGNAL) == static_cast<ssize_t>(line.size());
  }
  // streamed messages read so far plus whatever is waiting now (up to wait_ms for the first)
  std::vector<Json> take_messages(int wait_ms = 0) {
    for (double w = wait_ms / 1000.0;; w = 0.0) {
      auto m = read_one(w);
      if (!m) break;
      if (m->contains("event")) queue_.push_back(std::move(*m));
    }
    std::vector<Json> out;
    out.swap(queue_);
    return out;
  }
  bool alive() const { return alive_; }

 private:
  std::optional<Json> read_one(double wall_timeout_s) {
    for (;;) {
      const size_t nl = buf_.find('\n');
      if (nl != std::string::npos) {
        Json j = Json::parse(std::string_view(buf_.data(), nl), nullptr, false);
        buf_.erase(0, nl + 1);
        if (j.is_object()) return j;
        continue;
      }
      if (!alive_) return std::nullopt;
      pollfd p{fd_, POLLIN, 0};
      if (poll(&p, 1, static_cast<int>(wall_timeout_s * 1000)) <= 0) return std::nullopt;
      char tmp[65536];
      const ssize_t n = recv(fd_, tmp, sizeof(tmp), 0);
      if (n <= 0) {
        alive_ = false;
        return std::nullopt;
      }
      buf_.append(tmp, static_cast<size_t>(n));
    }
  }
  int fd_ = -1;
  int next_id_ = 0;
  bool alive_ = true;
  std::string buf_;
  std::vector<Json> queue_;
};

}  // namespace uavsim::missions::coverage::launch
