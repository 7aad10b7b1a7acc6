// The coverage scenario tests' run: coverage-run (COVERAGE_RUN) with five quads over 150 x 100 m,
// seed 1 unless extra names another, quiet, its summary read back (launcher_run.hpp); and the
// check of a flock that completed its mission.
#pragma once

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <string>

#include "../support/launcher_run.hpp"

namespace uavsim::tests {

// sim-time bound of a run: the fault-free mission takes ~180-210 s, one with a failure ~300 s
inline constexpr double kBudget_s = 900.0;
inline constexpr double kFullCoverage = 0.999;

inline nlohmann::json run_five_quads(const std::string& extra, std::string* output) {
  return run_launcher(std::string(COVERAGE_RUN) +
                          " --agents 5 --area 150x100 --seed 1 --quiet --budget " +
                          std::to_string(kBudget_s) + " --wall-limit 300",
                      extra, output);
}

// The run's summary r says the mission is done: the rectangle covered, no agent failed, all
// `agents` landed within budget_s of sim time, and the launcher's verdict is success; out is the
// run's output, shown with a failure.
inline void expect_complete_flock(const nlohmann::json& r, int agents, const std::string& out,
                                  double budget_s = kBudget_s) {
  EXPECT_GE(r["coverage"].get<double>(), kFullCoverage) << out;
  EXPECT_EQ(r["failed"].get<int>(), 0) << out;
  EXPECT_EQ(r["landed"].get<int>(), agents) << out;
  EXPECT_LT(r["mission_time_s"].get<double>(), budget_s) << out;
  EXPECT_TRUE(r["success"].get<bool>()) << out;
}

}  // namespace uavsim::tests
