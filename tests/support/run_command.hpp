// Runs a shell command to its end and keeps what it printed, for tests of a program's command line
// (exit codes, messages).
#pragma once

#include <sys/wait.h>

#include <cstdio>
#include <string>

namespace uavsim::testing {

struct CommandRun {
  int exit_code = -1;  // -1: not run, or ended by a signal
  std::string output;  // stdout and stderr
};

// cmd runs under /bin/sh with stderr joined to stdout.
inline CommandRun run_command(const std::string& cmd) {
  CommandRun r;
  FILE* p = popen((cmd + " 2>&1").c_str(), "r");
  if (p == nullptr) return r;
  char buf[4096];
  size_t n;
  while ((n = fread(buf, 1, sizeof(buf), p)) > 0) r.output.append(buf, n);
  const int status = pclose(p);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

inline bool has(const CommandRun& r, const std::string& s) { return r.output.find(s) != std::string::npos; }

}  // namespace uavsim::testing
