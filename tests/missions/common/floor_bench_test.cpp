// bench/mission_floor.py, which sets each mission beside its floor (--floor): run on MBZIRC 2017
// once, a whole mission and its floor (a scenario: a few seconds of wall time, and the mission's).
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <string>

#include "../../support/run_command.hpp"
#include "../support/launcher_run.hpp"

namespace {

using Json = nlohmann::json;
using uavsim::testing::run_command;
using uavsim::tests::take_file;

// The floor spans the mission's own sim time (from its summary), and each ratio is that run's
// mission wall time over its floor's.
TEST(MissionFloorBench, RunsTheMissionThenItsFloorForTheSameSimTime) {
  const std::string json = ::testing::TempDir() + "mission_floor_bench.json";
  const auto r =
      run_command("python3 " UAVSIM_SOURCE_DIR "/bench/mission_floor.py --build " UAVSIM_BUILD_DIR
                  " --cases mbzirc2017 --runs 1 --json " +
                  json);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const Json results = Json::parse(take_file(json), nullptr, false);
  ASSERT_TRUE(results.is_array() && results.size() == 1) << r.output;
  const Json& c = results[0];
  EXPECT_EQ(c.value("case", ""), "mbzirc2017");
  ASSERT_EQ(c["missions"].size(), 1u);
  ASSERT_EQ(c["floors"].size(), 1u);
  const Json& m = c["missions"][0];
  const Json& f = c["floors"][0];
  EXPECT_TRUE(m.value("success", false)) << r.output;
  EXPECT_GT(m.value("sim_s", 0.0), 30.0);  // the landing takes more than 30 s of sim time
  // the floor spans the mission's sim time (to the --floor argument's millisecond)
  EXPECT_NEAR(f.value("sim_s", 0.0), m.value("sim_s", 0.0), 1e-3);
  EXPECT_DOUBLE_EQ(c["ratios"][0].get<double>(), m.value("wall_s", 0.0) / f.value("wall_s", 1.0));
  EXPECT_NE(r.output.find("| mbzirc2017 |"), std::string::npos) << r.output;
}

}  // namespace
