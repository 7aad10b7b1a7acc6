// The whole MBZIRC 2017 landing (seed 7.1) in the simulator through its launcher: uavsim-server
// (headless, lockstep at full speed, the truck driven by a seeded person) and the UAV program.
// Scored from the sim API's ground truth (the launcher's JSON summary), never seen by the program.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <string>

#include "../support/launcher_run.hpp"

namespace {

using Json = nlohmann::json;

constexpr double kBudget_s = 240.0;            // sim seconds after the UAV's start
constexpr double kMaxRelativeSpeed_m_s = 1.0;  // the truck's landing limit
constexpr double kMaxMarkerDistance_m = 1.1;   // on the 2.2 m deck
// the propeller tips centred on the deck are 1.42 m from the cab (near_miss_test.cpp); a run that
// came within 0.3 m of it was lucky, not safe
constexpr double kMinCabClearance_m = 0.3;

Json run_mission(const std::string& extra, std::string* output) {
  return uavsim::tests::run_launcher(
      std::string(MBZIRC2017_RUN) + " --budget " + std::to_string(kBudget_s) + " --wall-limit 600",
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

// Zero contact with the cab or any truck part but the deck, and a clearance to the cab of at least
// kMinCabClearance_m all run long (ground truth at every lockstep tick); the figures are reported.
void expect_clear_of_the_cab(const Json& r, const std::string& out) {
  ASSERT_TRUE(r.is_object()) << out;
  EXPECT_EQ(r["truck_contacts"].get<int>(), 0) << out;
  ASSERT_TRUE(r["min_cab_clearance_m"].is_number()) << out;
  const double cab_m = r["min_cab_clearance_m"].get<double>();
  EXPECT_GT(cab_m, kMinCabClearance_m) << out;
  ::testing::Test::RecordProperty("min_cab_clearance_mm",
                                  static_cast<int>(std::lround(cab_m * 1e3)));
  std::printf("[ clearance ] cab %.3f m, skids to the deck's edges %s m, %d climb-away(s), %s\n",
              cab_m,
              r["min_deck_edge_margin_m"].is_number()
                  ? std::to_string(r["min_deck_edge_margin_m"].get<double>()).c_str()
                  : "-",
              r["climb_aways"].get<int>(), r["eight_part_at_touchdown"].dump().c_str());
}

// A run that lands and never comes near the cab.
Json land_clear_of_the_cab(const std::string& extra, std::string* out) {
  const Json r = run_mission(extra, out);
  expect_clear_of_the_cab(r, *out);
  if (r.is_object()) expect_landed(r, *out);
  return r;
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

// Issue 36: the UAV meets the truck anywhere on the eight, at any legal speed, in the field, and
// never touches it. Each start was picked (mbzirc2017-run --start-phase) for where the meeting
// falls.

// Touchdown in a curve of the eight (the truck turning under the UAV at 15 km/h: 0.21 rad/s).
TEST(Mbzirc2017Mission, MeetsTheTruckInACurveAndNeverTouchesTheCab) {
  std::string out;
  const Json r = land_clear_of_the_cab("--seed 11 --start-phase 0.25 --realism field", &out);
  EXPECT_EQ(r["eight_part_at_touchdown"], "curve") << out;
}

// The approach begins at the crossing of the eight, where the other branch passes under the UAV.
TEST(Mbzirc2017Mission, MeetsTheTruckAtTheCrossingAndNeverTouchesTheCab) {
  std::string out;
  const Json r = land_clear_of_the_cab("--seed 12 --start-phase 0.5 --realism field", &out);
  EXPECT_EQ(r["eight_part_at_approach"], "crossing") << out;
}

// The rules' fastest truck, 20 km/h (5.6 m/s), in the field.
TEST(Mbzirc2017Mission, LandsAtTwentyKmhAndNeverTouchesTheCab) {
  std::string out;
  const Json r = land_clear_of_the_cab(
      "--seed 13 --truck-speed-kmh 20 --start-phase 0.75 --realism field", &out);
  EXPECT_DOUBLE_EQ(r["truck_speed_kmh"].get<double>(), 20.0);
}

// The crash: the marker lost 1 m above the deck while the UAV's estimate has it 1 m off the
// centre (its GPS 1 m off towards the truck's rear, its control pulling it towards the cab). No
// open-loop descent from there: it climbs away, never touches the cab, and lands on a later
// approach.
TEST(Mbzirc2017Mission, MarkerLostLowAndOffCentreClimbsAwayAndLandsLater) {
  std::string out;
  const Json r = land_clear_of_the_cab("--seed 14 --lose-low-off-centre --realism field", &out);
  ASSERT_TRUE(r.is_object()) << out;
  EXPECT_GE(r["lose_low_off_centre_at_s"].get<double>(), 0.0) << out;
  EXPECT_GE(r["climb_aways"].get<int>(), 1) << out;
  // the marker is out of view by then (too close): the open loop leaves the deck box in the UAV's
  // own estimate, or the loss comes before it began; either way the climb-away
  EXPECT_NE(out.find("climb-away:"), std::string::npos) << out;
  EXPECT_GT(r["touchdown_time_s"].get<double>(), r["lose_low_off_centre_at_s"].get<double>());
}

// The sampled sweep's one cab contact (seed 52: 5.3 km/h on the straight, field): a GPS jump 1.2 s
// into the blind last metres, centred and matched 0.36 m above the deck. The FC blends the step in
// and, flying its stepped estimate, drifts the UAV 1.1 m forward in a second; the climb-away taken
// on that estimate put a propeller in the cab. Now the program notices the step and, that low, cuts
// the motors onto the deck.
TEST(Mbzirc2017Mission, GpsJumpInTheBlindLastMetresLandsWithoutTouchingTheCab) {
  std::string out;
  const Json r = land_clear_of_the_cab(
      "--seed 52 --start-phase random --truck-speed-kmh random --random-blackouts 2 --realism "
      "field",
      &out);
  ASSERT_TRUE(r.is_object()) << out;
  EXPECT_GE(r["estimate_steps"].get<int>(), 1) << out;
  EXPECT_NE(out.find("motors off onto the deck"), std::string::npos) << out;
  ASSERT_TRUE(r["min_deck_edge_margin_m"].is_number()) << out;
  EXPECT_GT(r["min_deck_edge_margin_m"].get<double>(), 0.0) << out;
}

// The 303-run sampled sweep's cab contact (seed 172: 8.3 km/h on the straight, field): a GPS jump
// 1.2 m above the deck, just before the blind last metres. The step was noticed and the UAV held,
// but when the estimate had settled the program went on with the truck's track made before the
// step, ~2 m off against its position after it: a blind descent "centred" 1.7 m ahead of the
// marker, onto the cab's corner. Now the track is made again from sightings taken after the
// estimate settled, with no descent until then, and the UAV lands on a later approach.
TEST(Mbzirc2017Mission, GpsJumpLowOverTheDeckMakesTheTrackAgainAndNeverTouchesTheCab) {
  std::string out;
  const Json r = land_clear_of_the_cab(
      "--seed 172 --start-phase random --truck-speed-kmh random --random-blackouts 2 --realism "
      "field",
      &out);
  ASSERT_TRUE(r.is_object()) << out;
  EXPECT_GE(r["estimate_steps"].get<int>(), 1) << out;
  EXPECT_NE(out.find("made again from new sightings"), std::string::npos) << out;
}

// The sweep's other truck contact (seed 148: 5.5 km/h on the straight, field, no step noticed): the
// barometer 0.36 m above the truth as the marker left the image, so the floor's rule never held in
// the blind last metres; drifting back against the truck at 0.9 m/s, the UAV slid off the deck's
// rear edge and a propeller hit the deck from below. Now the blind height decides and the blind
// correction is gentle: no contact with any part of the truck.
TEST(Mbzirc2017Mission, BarometerHighInTheBlindLastMetresNeverTouchesTheTruck) {
  std::string out;
  const Json r = run_mission(
      "--seed 148 --start-phase random --truck-speed-kmh random --random-blackouts 2 --realism "
      "field",
      &out);
  expect_clear_of_the_cab(r, out);
  ASSERT_TRUE(r.is_object()) << out;
  EXPECT_TRUE(r["crashes"].empty()) << out;
}

// End-of-run determinism: the launcher's clock stops by itself at the end (pause_at: 5 s on the
// deck, the program gone or the budget spent), so two runs of one seed under field conditions give
// the same event log and the same summary to the byte (wall time aside).
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
