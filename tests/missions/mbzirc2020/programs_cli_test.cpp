// The mission's own programs on a command line they cannot run: --help says the usage and exits;
// an option without its value is a usage error, never skipped (mbzirc2020-gcs used to skip a lone
// option and start a ground station that waited for UAVs).
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdio>
#include <string>

namespace {

struct ProgramRun {
  int exit_code = -1;
  std::string output;  // stdout and stderr
};

ProgramRun run(const std::string& command_line) {
  ProgramRun r;
  // a program that would wait for UAVs instead is ended by timeout (exit code 124)
  std::FILE* p = popen(("timeout 10 " + command_line + " 2>&1").c_str(), "r");
  if (p == nullptr) return r;
  char buf[512];
  while (std::fgets(buf, sizeof(buf), p) != nullptr) r.output += buf;
  const int status = pclose(p);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

TEST(Mbzirc2020Programs, GcsHelpSaysItsUsageAndExits) {
  for (const char* flag : {"--help", "-h"}) {
    const ProgramRun r = run(std::string(MBZIRC2020_GCS) + " " + flag);
    EXPECT_EQ(r.exit_code, 0) << flag << ": " << r.output;
    EXPECT_EQ(r.output.rfind("usage: mbzirc2020-gcs", 0), 0u) << r.output;
  }
}

TEST(Mbzirc2020Programs, AnOptionWithoutItsValueIsAUsageError) {
  for (const std::string args : {"--uavs", "--uavs 2 --max-time", "--uavs 0", "--bogus 1"}) {
    const ProgramRun r = run(std::string(MBZIRC2020_GCS) + " " + args);
    EXPECT_EQ(r.exit_code, 2) << args << ": " << r.output;
    EXPECT_NE(r.output.find("usage: mbzirc2020-gcs"), std::string::npos) << r.output;
  }
  for (const std::string args :
       {"--help", "--index 0 --mavlink tcp:127.0.0.1:1 --gcs 127.0.0.1:2 --camera",
        "--mavlink tcp:127.0.0.1:1 --gcs 127.0.0.1:2 --index"}) {
    const ProgramRun r = run(std::string(MBZIRC2020_UAV) + " " + args);
    EXPECT_EQ(r.exit_code, 2) << args << ": " << r.output;
    EXPECT_NE(r.output.find("usage: mbzirc2020-uav"), std::string::npos) << r.output;
  }
}

}  // namespace
