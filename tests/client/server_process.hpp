// uavsim-server (the UAVSIM_SERVER program) as a subprocess for the client tests that need the
// real program: its world, free-running ("--rate 0"), on ephemeral ports read from its banner.
#pragma once

#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <regex>
#include <string>
#include <vector>

extern char** environ;

namespace uavsim::client::testing {

class ServerProcess {
 public:
  // the server on `world` with `extra` options after the ports'; its ports are 0 when it did not
  // start (output() then says why)
  ServerProcess(const std::string& world, const std::vector<std::string>& extra) {
    std::vector<std::string> args{UAVSIM_SERVER,    world, "--rate",     "0",
                                  "--mavlink-port", "0",   "--api-port", "0"};
    args.insert(args.end(), extra.begin(), extra.end());
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    int fds[2];
    if (pipe(fds) != 0) return;
    posix_spawn_file_actions_t fa;
    posix_spawn_file_actions_init(&fa);
    posix_spawn_file_actions_adddup2(&fa, fds[1], 1);
    posix_spawn_file_actions_addclose(&fa, fds[0]);
    if (posix_spawn(&pid_, argv[0], &fa, nullptr, argv.data(), environ) != 0) pid_ = -1;
    posix_spawn_file_actions_destroy(&fa);
    close(fds[1]);
    out_ = fdopen(fds[0], "r");
    // the banner: the MAVLink port, then the API's, the last line waited for
    char line[1024];
    const std::regex api(R"(sim API on tcp:[0-9.]+:(\d+))");
    const std::regex mav(R"(MAVLink on tcp:[0-9.]+:(\d+))");
    while (pid_ > 0 && fgets(line, sizeof(line), out_) != nullptr) {
      output_ += line;
      std::cmatch m;
      if (std::regex_search(line, m, mav) && mavlink_port_ == 0) mavlink_port_ = std::stoi(m[1]);
      if (std::regex_search(line, m, api)) {
        port_ = std::stoi(m[1]);
        break;
      }
    }
  }
  ~ServerProcess() {
    if (pid_ > 0) {
      kill(pid_, SIGTERM);
      waitpid(pid_, nullptr, 0);
    }
    if (out_ != nullptr) fclose(out_);
  }
  ServerProcess(const ServerProcess&) = delete;
  ServerProcess& operator=(const ServerProcess&) = delete;

  int api_port() const { return port_; }
  int mavlink_port() const { return mavlink_port_; }
  // what it printed up to its API's port
  const std::string& output() const { return output_; }

 private:
  pid_t pid_ = -1;
  FILE* out_ = nullptr;
  int port_ = 0;
  int mavlink_port_ = 0;
  std::string output_;
};

}  // namespace uavsim::client::testing
