// The mission scenario tests' one way to run a launcher (mbzirc2017-run, mbzirc2020-run,
// coverage-run): as a child process, its output kept for the failure message, its summary read
// back from the --json file it writes. The summary is scored by the launcher from the sim API's
// ground truth, which the mission programs never see.
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <string>

namespace uavsim::tests {

// The whole text of a file, which is then removed ("" if there is none).
inline std::string take_file(const std::string& path) {
  std::ifstream in(path);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::remove(path.c_str());
  return text;
}

// Runs `command --no-run-dir extra --json FILE` (stdout and stderr into *output) and returns the
// summary it wrote, or a null JSON value when it wrote none (the output says why). No run
// directory (the launchers make one under ./runs by default): the tests leave nothing behind.
inline nlohmann::json run_launcher(const std::string& command, const std::string& extra,
                                   std::string* output) {
  static int run = 0;
  const std::string json_path = ::testing::TempDir() + "launcher_" + std::to_string(getpid()) +
                                "_" + std::to_string(run++) + ".json";
  std::remove(json_path.c_str());
  const std::string cmd = command + " --no-run-dir --json " + json_path + " " + extra + " 2>&1";
  FILE* p = popen(cmd.c_str(), "r");
  if (p == nullptr) return nlohmann::json();
  char buf[1024];
  while (fgets(buf, sizeof(buf), p) != nullptr) *output += buf;
  pclose(p);
  return nlohmann::json::parse(take_file(json_path), nullptr, false);
}

}  // namespace uavsim::tests
