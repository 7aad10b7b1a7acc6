// A program started as a child process with its stdout and stderr on one pipe, for tests that read
// what a server or launcher prints while it runs.
#pragma once

#include <unistd.h>

#include <functional>
#include <string>
#include <vector>

namespace uavsim::testing {

// Starts args (args[0] is the program's path) with stdout and stderr on one pipe whose read end
// goes to *read_fd. before_exec, if given, runs in the child just before the exec: only
// async-signal-safe calls there (setrlimit, signal). Returns the child's pid; -1 (and *read_fd -1)
// when the pipe or the fork fails. The child exits 127 when the program cannot be run.
inline pid_t spawn_piped(std::vector<std::string> args, int* read_fd,
                         const std::function<void()>& before_exec = {}) {
  *read_fd = -1;
  int fds[2];
  if (pipe(fds) != 0) return -1;
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  const pid_t pid = fork();
  if (pid == 0) {
    dup2(fds[1], 1);
    dup2(fds[1], 2);
    close(fds[0]);
    close(fds[1]);
    if (before_exec) before_exec();
    execv(argv[0], argv.data());
    _exit(127);
  }
  close(fds[1]);
  if (pid < 0) {
    close(fds[0]);
    return -1;
  }
  *read_fd = fds[0];
  return pid;
}

}  // namespace uavsim::testing
