// The whole MBZIRC 2017 landing (seed 7.1) in the simulator through its launcher: uavsim-server
// (headless, lockstep at full speed, the truck driven by a seeded person) and the UAV program.
// Scored from the sim API's ground truth (the launcher's JSON summary), never seen by the program.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <string>

#include "../support/launcher_run.hpp"

namespace {

using Json = nlohmann::json;

constexpr double kBudget_s = 240.0;            // sim seconds after the UAV's start
constexpr double kMaxRelativeSpeed_m_s = 1.0;  // the truck's landing limit
constexpr double kMaxMarkerDistance_m = 1.1;   // on the 2.2 m deck

Json run_mission(const std::string& extra, std::string* output) {
  return uavsim::tests::run_launcher(std::string(MBZIRC2017_RUN) + " --budget " +
                                         std::to_string(kBudget_s) + " --wall-limit 600",
                                     extra, output);
}

void expect_landed(const Json& r, const std::string& out) {
  ASSERT_TRUE(r.is_object()) << out;
  EXPECT_TRUE(r["landed"].get<bool>()) << out;
  EXPECT_TRUE(r["stayed_on_deck"].get<bool>()) << out;
  EXPECT_TRUE(r["crashes"].empty()) << out;
  EXPECT_GT(r["mission_time_s"].get<double>(), 0.0) << out;
  EXPECT_LT(r["relative_speed_m_s"].get<double>(), kMaxRelativeSpeed_m_s) << out;
  EXPECT_LT(r["marker_distance_m"].get<double>(), kMaxMarkerDistance_m) << out;
  EXPECT_TRUE(r["success"].get<bool>()) << out;
}

bool went_through(const Json& r, const std::string& state) {
  const Json& s = r["states"];
  return std::find(s.begin(), s.end(), Json(state)) != s.end();
}

TEST(Mbzirc2017Mission, LandsOnTheTruckAtFifteenKmh) {
  std::string out;
  const Json r = run_mission("--seed 1", &out);
  expect_landed(r, out);
  EXPECT_TRUE(went_through(r, "Approach")) << out;
}

TEST(Mbzirc2017Mission, LandsInTheFiveKmhPhase) {
  std::string out;
  const Json r = run_mission("--seed 2 --phase slow", &out);
  expect_landed(r, out);
  EXPECT_DOUBLE_EQ(r["start_time_s"].get<double>(), 480.0);
  EXPECT_GT(r["takeoff_time_s"].get<double>(), 480.0);
}

// The camera black for 14 s as the UAV first sets off to intercept the truck: the first pass is
// lost (12 s unseen in Wait Until Visible, or 8 s lost in Approach), the FSM intercepts again and
// the UAV still lands.
TEST(Mbzirc2017Mission, BlackedOutFirstPassInterceptsAgainAndStillLands) {
  std::string out;
  const Json r = run_mission("--seed 3 --blackout-first-pass", &out);
  ASSERT_TRUE(r.is_object()) << out;
  EXPECT_GE(r["blackout_first_pass_at_s"].get<double>(), 0.0) << out;
  const Json& s = r["states"];
  EXPECT_GE(std::count(s.begin(), s.end(), Json("Intercept")), 2) << out;
  expect_landed(r, out);
}

// The truck lost from the camera's view during Approach (4 s black): the UAV climbs and re-acquires
// it, or goes back to Go To Centre; it never crashes, and here it still lands.
TEST(Mbzirc2017Mission, TruckLostDuringApproachClimbsReacquiresAndNeverCrashes) {
  std::string out;
  const Json r = run_mission("--seed 4 --lose-in-approach", &out);
  ASSERT_TRUE(r.is_object()) << out;
  EXPECT_GE(r["blackout_approach_at_s"].get<double>(), 0.0) << out;
  EXPECT_TRUE(r["crashes"].empty()) << out;
  EXPECT_NE(out.find("marker lost"), std::string::npos) << out;
  expect_landed(r, out);
}

// End-of-run determinism: the launcher's clock stops by itself at the end (pause_at: 5 s on the deck,
// the program gone or the budget spent), so two runs of one seed under field conditions give the
// same event log and the same summary to the byte (wall time aside).
TEST(Mbzirc2017Mission, SameSeedInTheFieldGivesTheSameRunToTheByte) {
  const std::string events = ::testing::TempDir() + "mbzirc2017_events_" + std::to_string(getpid());
  std::string out[2], log[2];
  Json r[2];
  for (int k = 0; k < 2; ++k) {
    r[k] = run_mission("--seed 6 --realism field --events " + events, &out[k]);
    log[k] = uavsim::tests::take_file(events);
    ASSERT_TRUE(r[k].is_object()) << out[k];
    r[k].erase("wall_time_s");
  }
  EXPECT_FALSE(log[0].empty());
  EXPECT_EQ(log[0], log[1]);
  EXPECT_EQ(r[0].dump(2), r[1].dump(2)) << out[0] << out[1];
  EXPECT_TRUE(r[0]["landed"].get<bool>()) << out[0];
}

}  // namespace
