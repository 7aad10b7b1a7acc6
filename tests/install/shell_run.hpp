// The install tests' one way to run a shell command line: its exit status and its output (stdout
// and stderr together), kept for the failure message.
#pragma once

#include <sys/wait.h>

#include <cstdio>
#include <string>

namespace uavsim::tests {

struct ShellRun {
  int exit_code = -1;  // -1: not started, or ended by a signal
  std::string output;
};

inline ShellRun run_shell(const std::string& cmd) {
  ShellRun r;
  FILE* p = popen((cmd + " 2>&1").c_str(), "r");
  if (p == nullptr) return r;
  char buf[4096];
  for (size_t n; (n = fread(buf, 1, sizeof(buf), p)) > 0;) r.output.append(buf, n);
  const int status = pclose(p);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

}  // namespace uavsim::tests
