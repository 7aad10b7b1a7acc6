// The coverage scenario tests' run: coverage-run (COVERAGE_RUN) with five quads over 150 x 100 m,
// seed 1 unless extra names another, quiet, its summary read back (launcher_run.hpp).
#pragma once

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

}  // namespace uavsim::tests
