// The coverage flock in the simulator through its launcher (coverage-run): uavsim-server on a
// generated world of five quads, one coverage-agent process per quad on MAVLink and the
// simulator's radio, lockstep at full speed, seeded. Scored from the launcher's JSON summary:
// coverage of the data the surviving agents hold, landings and failures from the sim API's
// ground truth (the agents never see it). Each run is 150 x 100 m: ~210 s of sim time, 10-20 s of
// wall time here.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "five_quads_run.hpp"

namespace {

constexpr double kFailTimeTol_s = 0.1;
constexpr double kFractionTol = 1e-3;
constexpr double kCompleteTol_s = 0.5;    // coverage complete within a tick or two
constexpr double kMissionTol_s = 6.0;     // take-offs and landings move with the host's load
constexpr double kDistanceRelTol = 0.01;  // of the flock's total distance
constexpr double kTickTol_s = 1e-6;       // a sim time on a whole tick

using Json = nlohmann::json;
using uavsim::tests::kBudget_s;
using uavsim::tests::kFullCoverage;

Json run_flock(const std::string& extra, std::string* output) {
  return uavsim::tests::run_five_quads(extra, output);
}

void expect_every_survivor_landed(const Json& r, const std::string& out) {
  for (const Json& a : r["per_agent"]) {
    if (!a["failed"].get<bool>()) EXPECT_TRUE(a["landed"].get<bool>()) << a.dump() << out;
  }
}

TEST(CoverageRun, FiveQuadsCoverTheRectangleAndLand) {
  std::string out;
  const Json r = run_flock("", &out);
  ASSERT_TRUE(r.is_object()) << out;
  uavsim::tests::expect_complete_flock(r, 5, out);
  EXPECT_EQ(r["completed_by"].get<int>(), 0) << out;
  EXPECT_GT(r["mission_time_s"].get<double>(), 0.0) << out;
  // every quad flew and used its battery (3S, 5000 mAh: thesis eqs. 4.6-4.9)
  for (const Json& a : r["per_agent"]) {
    EXPECT_GT(a["energy_mah"].get<double>(), 100.0) << a.dump();
    EXPECT_LT(a["energy_mah"].get<double>(), 5000.0) << a.dump();
    EXPECT_GT(a["held_fraction"].get<double>(), 0.1) << a.dump();
  }
  // nobody failed: nothing was lost, nothing flown to recover it (table 4.3's measure)
  EXPECT_EQ(r["recovery_distance_m"].get<double>(), 0.0) << out;
  EXPECT_EQ(r["recovered_fraction"].get<double>(), 0.0) << out;
}

// Fig. 4.6: the leader (agent 0) dies mid-mission; agent 1 ages it out of its ADB, becomes the
// leader, and its query finds the rectangle covered by the survivors' data.
TEST(CoverageRun, LeaderKilledMidMissionANewLeaderFinishes) {
  std::string out;
  const Json r = run_flock("--kill 0@60", &out);
  ASSERT_TRUE(r.is_object()) << out;
  EXPECT_EQ(r["killed"], Json::array({0})) << out;
  EXPECT_EQ(r["completed_by"].get<int>(), 1) << out;
  EXPECT_EQ(r["leaders"], Json::array({0, 1})) << out;
  EXPECT_GE(r["coverage"].get<double>(), kFullCoverage) << out;
  expect_every_survivor_landed(r, out);
  EXPECT_TRUE(r["success"].get<bool>()) << out;
}

// A non-leader dies after it took pictures: its data is lost with it, and the flock covers its
// stripes again (the survivors' data alone covers the rectangle).
TEST(CoverageRun, NonLeaderKilledItsStripesAreCoveredAgain) {
  std::string out;
  const Json r = run_flock("--kill 3@70", &out);
  ASSERT_TRUE(r.is_object()) << out;
  EXPECT_EQ(r["killed"], Json::array({3})) << out;
  const Json& dead = r["per_agent"][3];
  EXPECT_TRUE(dead["failed"].get<bool>()) << out;
  EXPECT_GT(dead["held_fraction"].get<double>(), 0.05) << out;  // it had data, now lost
  EXPECT_GE(r["coverage"].get<double>(), kFullCoverage) << out;
  // what it alone held (measured: 6.2 % of the rectangle) was photographed again, all of it, by
  // agents flying 93 m of their 4912 m over it (table 4.3's "distance flown to recover")
  EXPECT_GT(r["recovered_fraction"].get<double>(), 0.02) << out;
  EXPECT_LT(r["lost_fraction_at_end"].get<double>(), 1e-3) << out;
  // the loss is recorded with the failure: when, and how much died with it (part of what it held,
  // the rest was under its neighbours' pictures too), all of it recovered
  EXPECT_NEAR(dead["failed_at_s"].get<double>(), 70.0, kFailTimeTol_s) << out;
  const double lost = dead["lost_fraction"].get<double>();
  EXPECT_GT(lost, 0.02) << out;
  EXPECT_LE(lost, dead["held_fraction"].get<double>()) << out;
  EXPECT_EQ(r["lost_at_failures_fraction"].get<double>(), lost) << out;
  EXPECT_NEAR(r["recovered_fraction"].get<double>(), lost, kFractionTol) << out;
  EXPECT_GT(r["recovery_distance_m"].get<double>(), 0.0) << out;
  EXPECT_LT(r["recovery_distance_m"].get<double>(), 0.1 * r["distance_m_total"].get<double>())
      << out;
  expect_every_survivor_landed(r, out);
  EXPECT_TRUE(r["success"].get<bool>()) << out;
}

// A non-leader dies on the way home (the going-home broadcast of this seed goes out at 132.9 s):
// the pictures only it held die with it. The leader, having aged it out, queries the flock again,
// finds the rectangle no longer covered and recalls the agents still flying, which cover the lost
// part; then everyone lands. Without the recall the run ends below 100 % (scored a failure).
TEST(CoverageRun, NonLeaderKilledOnTheWayHomeTheFlockGoesBackForItsPictures) {
  std::string out;
  const Json r = run_flock("--kill 3@138", &out);
  ASSERT_TRUE(r.is_object()) << out;
  EXPECT_EQ(r["killed"], Json::array({3})) << out;
  EXPECT_EQ(r["recalls"].get<int>(), 1) << out;
  EXPECT_GT(r["coverage_complete_s"].get<double>(), 138.0) << out;  // completed again, after it
  EXPECT_GE(r["coverage"].get<double>(), kFullCoverage) << out;
  expect_every_survivor_landed(r, out);
  EXPECT_TRUE(r["success"].get<bool>()) << out;
}

// The leader lands last (it hovers over its home until the others have landed); killed in its final
// descent (at 177.5 s, 2 m up: its LAND runs from 176 s to 179 s in this seed), it takes its
// pictures with it and nobody is left flying. The lowest id landed (1) sees it age out, queries the
// landed agents, takes off again alone and covers what was lost, merging what the landed agents
// hold into its queries from afar.
TEST(CoverageRun, LastFlyerKilledInItsDescentTheLowestLandedTakesOffAgain) {
  std::string out;
  const Json r = run_flock("--kill 0@177.5", &out);
  ASSERT_TRUE(r.is_object()) << out;
  EXPECT_EQ(r["killed"], Json::array({0})) << out;
  EXPECT_EQ(r["recalls"].get<int>(), 1) << out;
  EXPECT_EQ(r["completed_by"].get<int>(), 1) << out;
  EXPECT_GT(r["coverage_complete_s"].get<double>(), 177.5) << out;  // completed again, after it
  EXPECT_GE(r["coverage"].get<double>(), kFullCoverage) << out;
  expect_every_survivor_landed(r, out);
  EXPECT_TRUE(r["success"].get<bool>()) << out;
}

// 30 % of the frames heard are lost (seeded): beacons and the aggregation query's retransmissions
// still get the flock's map to the leader.
TEST(CoverageRun, ThirtyPercentRadioLossStillCoversEverything) {
  std::string out;
  const Json r = run_flock("--radio-loss 0.3", &out);
  ASSERT_TRUE(r.is_object()) << out;
  EXPECT_GE(r["coverage"].get<double>(), kFullCoverage) << out;
  EXPECT_EQ(r["landed"].get<int>(), 5) << out;
  EXPECT_TRUE(r["success"].get<bool>()) << out;
}

// All five agents in one coverage-agent process (--vehicles 0-4): each still has its own MAVLink
// link and radio, frames between them go through the simulated radio, and its commands do not block
// (a blocking take-off of one agent used to hold the others' steps: the mission then varied from
// 172 to 189 s), so the flock flies the mission of one process per agent.
TEST(CoverageRun, OneProcessFlyingAllFiveAgentsFliesTheMissionOfOneProcessEach) {
  std::string out_one, out_each;
  const Json one = run_flock("--per-process 5", &out_one);
  const Json each = run_flock("", &out_each);
  ASSERT_TRUE(one.is_object()) << out_one;
  ASSERT_TRUE(each.is_object()) << out_each;
  EXPECT_GE(one["coverage"].get<double>(), kFullCoverage) << out_one;
  EXPECT_EQ(one["landed"].get<int>(), 5) << out_one;
  EXPECT_TRUE(one["success"].get<bool>()) << out_one;
  // the same passes: coverage complete within a tick or two. The take-offs and the landings still
  // move by a few tenths to a few seconds with the host's load (one process: 177.7-180.9 s, one per
  // agent: 177.8 s, idle and loaded): the links of one process come up one after the other.
  EXPECT_NEAR(one["coverage_complete_s"].get<double>(), each["coverage_complete_s"].get<double>(),
              kCompleteTol_s)
      << out_one << out_each;
  EXPECT_NEAR(one["mission_time_s"].get<double>(), each["mission_time_s"].get<double>(),
              kMissionTol_s)
      << out_one << out_each;
  EXPECT_NEAR(one["distance_m_total"].get<double>(), each["distance_m_total"].get<double>(),
              kDistanceRelTol * each["distance_m_total"].get<double>())
      << out_one << out_each;
}

// The optimised variant (thesis 3.6): the agents send what they acquire to a ground station
// (coverage-gcs) over their GCS links, through the server's relay; the station sends its map back.
// Without failures the flock flies the plain variant's mission, and the station ends up with
// every picture.
TEST(CoverageRun, WithAGroundStationTheFlockCoversTheRectangleAndTheStationHasItAll) {
  std::string out;
  const Json r = run_flock("--gcs", &out);
  ASSERT_TRUE(r.is_object()) << out;
  EXPECT_TRUE(r["gcs"].get<bool>()) << out;
  EXPECT_GE(r["coverage"].get<double>(), kFullCoverage) << out;
  EXPECT_GE(r["gcs_held_fraction"].get<double>(), kFullCoverage) << out;
  EXPECT_EQ(r["landed"].get<int>(), 5) << out;
  ASSERT_EQ(r["gcs_links"].size(), 5u) << out;
  for (const Json& g : r["gcs_links"]) {
    EXPECT_GT(g["to_gcs_forwarded"].get<int>(), 0) << g.dump();
    EXPECT_GT(g["to_uav_forwarded"].get<int>(), 0) << g.dump();
  }
  EXPECT_TRUE(r["success"].get<bool>()) << out;
}

// A non-leader dies holding pictures that reached the station: the leader's map (query result
// merged with the station's) already has them, so the flock does not fly them again and finishes
// sooner, over a shorter distance, than in the plain variant's same run (measured: 270.4 s and
// 4389 m against 297.1 s and 4846 m).
TEST(CoverageRun, WithAGroundStationADeadAgentsDeliveredPicturesAreNotFlownAgain) {
  std::string out, plain_out;
  const Json r = run_flock("--gcs --kill 3@70", &out);
  const Json plain = run_flock("--kill 3@70", &plain_out);
  ASSERT_TRUE(r.is_object()) << out;
  ASSERT_TRUE(plain.is_object()) << plain_out;
  EXPECT_EQ(r["killed"], Json::array({3})) << out;
  EXPECT_GT(r["per_agent"][3]["held_fraction"].get<double>(), 0.05) << out;
  EXPECT_GE(r["coverage"].get<double>(), kFullCoverage) << out;
  EXPECT_LT(r["mission_time_s"].get<double>(), plain["mission_time_s"].get<double>()) << out;
  EXPECT_LT(r["distance_m_total"].get<double>(), plain["distance_m_total"].get<double>()) << out;
  // only its last undelivered pictures were lost (measured: 2.5 m flown to recover them, against
  // 93 m in the plain variant)
  EXPECT_LT(r["recovery_distance_m"].get<double>(),
            0.2 * plain["recovery_distance_m"].get<double>())
      << out;
  expect_every_survivor_landed(r, out);
  EXPECT_TRUE(r["success"].get<bool>()) << out;
}

// The station's links are cut (the relay drops every datagram) at 60 s, before agent 3 dies at 70 s
// with pictures the station never got: the flock degrades to the plain variant and covers them
// again (thesis 3.6: tolerant to the failure of any agent, the GCS included).
TEST(CoverageRun, GroundStationLinksCutMidMissionTheFlockStillCompletes) {
  std::string out;
  const Json r = run_flock("--gcs --gcs-cut 60 --kill 3@70", &out);
  ASSERT_TRUE(r.is_object()) << out;
  EXPECT_LT(r["gcs_held_fraction"].get<double>(), 0.6) << out;  // what it had at 60 s
  for (const Json& g : r["gcs_links"]) EXPECT_GT(g["to_gcs_dropped"].get<int>(), 0) << g.dump();
  EXPECT_GE(r["coverage"].get<double>(), kFullCoverage) << out;
  expect_every_survivor_landed(r, out);
  EXPECT_TRUE(r["success"].get<bool>()) << out;
}

// Seeded failures (every 10 s each flying agent fails with probability p) and lossy radio, twice
// on a smaller rectangle: the same seed gives the same run (failures, mission time, energy), bit
// for bit. (Whether it succeeds is not the point: with this seed agent 4 fails at 60 s, its
// stripes are flown again, and agent 1 fails at 130 s on its way home, after the flock completed,
// and its pictures are lost with it.)
// The whole summary (what the launcher writes, wall time and the run's paths aside): what stays
// the same from run to run of a seed.
std::string whole_summary(Json r) {
  for (const char* field : {"wall_time_s", "run_dir", "video"}) r.erase(field);
  return r.dump(2);
}

TEST(CoverageRun, SameSeedSameRunWithFailuresAndLoss) {
  std::string out1, out2;
  const std::string args = "--area 100x60 --failure-prob 0.03 --radio-loss 0.2 --seed 3";
  const Json a = run_flock(args, &out1);
  const Json b = run_flock(args, &out2);
  ASSERT_TRUE(a.is_object()) << out1;
  ASSERT_TRUE(b.is_object()) << out2;
  EXPECT_FALSE(a["killed"].empty()) << out1;
  // failures, the recovery meter, mission time, energy, the end of the run: all of it
  EXPECT_EQ(whole_summary(a), whole_summary(b)) << out1 << out2;
}

// Five quads, seed 7, each run with a run directory of its own (ground truth recorded, as a sweep
// runs them): the run ends at the first of the launcher's ticks after every agent's end, whenever
// the programs' exits are noticed, and the time in each state is summed in the agents' order, so
// the two summaries are the same to the byte (they once ended 188.200 s and 188.202 s, and summed
// 45.75 s of "Taking Off" as 45.74999999999999).
TEST(CoverageRun, SameSeedGivesTheSameWholeSummaryToTheByte) {
  std::string out[2];
  Json r[2];
  for (int k = 0; k < 2; ++k) {
    const std::string dir = ::testing::TempDir() + "coverage_repro_" + std::to_string(getpid()) +
                            "_" + std::to_string(k);
    r[k] = run_flock("--seed 7 --no-record --run-dir " + dir, &out[k]);
    ASSERT_TRUE(r[k].is_object()) << out[k];
    EXPECT_EQ(r[k]["run_dir"].get<std::string>(), dir);
  }
  EXPECT_TRUE(r[0]["success"].get<bool>()) << out[0];
  // the end is one of the launcher's 1 s ticks
  const double end_s = r[0]["sim_time_s"].get<double>();
  EXPECT_NEAR(end_s, std::round(end_s), kTickTol_s) << out[0];
  EXPECT_GT(end_s, r[0]["last_touchdown_s"].get<double>()) << out[0];
  EXPECT_EQ(whole_summary(r[0]), whole_summary(r[1])) << out[0] << out[1];
}

// The agents' lockstep over the shared-memory stream (UAVSIM_API_TRANSPORT=shm: an agent that
// cannot use it fails) and over TCP: the same seeded run, to the byte, summary and event log
// (docs/protocol.md, "Shared-memory stream"), with radio loss so that the radio's draws are in it.
TEST(CoverageRun, SharedMemoryAndTcpGiveTheSameRunToTheByte) {
  std::string out[2];
  Json r[2];
  std::string events[2];
  const char* transports[2] = {"tcp", "shm"};
  for (int k = 0; k < 2; ++k) {
    const std::string dir = ::testing::TempDir() + "coverage_transport_" +
                            std::to_string(getpid()) + "_" + transports[k];
    r[k] = uavsim::tests::run_launcher(
        std::string("UAVSIM_API_TRANSPORT=") + transports[k] + " " + COVERAGE_RUN +
            " --agents 3 --area 60x40 --seed 5 --quiet --budget 600 --wall-limit 300",
        "--radio-loss 0.1 --no-record --run-dir " + dir, &out[k]);
    ASSERT_TRUE(r[k].is_object()) << out[k];
    // the flight's events; not the MAVLink clients' connects and leaves, whose ports differ in any
    // two runs and whose leaving is seen at the step where the server notices an exited agent's
    // socket
    std::istringstream log(uavsim::tests::take_file(dir + "/events.jsonl"));
    for (std::string line; std::getline(log, line);) {
      if (line.find("\"event\":\"client_") == std::string::npos) events[k] += line + "\n";
    }
  }
  EXPECT_TRUE(r[1]["success"].get<bool>()) << out[1];
  EXPECT_FALSE(events[0].empty());
  EXPECT_EQ(events[0], events[1]);
  EXPECT_EQ(whole_summary(r[0]), whole_summary(r[1])) << out[0] << out[1];
}

// The agents with a one-tick compute latency (coverage-agent --pipelined: their outputs go out at
// the next tick while the simulator steps on): the flock still covers everything and lands, and a
// run repeats to the last bit, with loss, though the simulator no longer waits for the agents'
// work at each tick.
TEST(CoverageRun, PipelinedAgentsCoverTheRectangleAndTheRunRepeats) {
  std::string out1, out2;
  const std::string args = "--area 100x60 --radio-loss 0.2 --seed 4 --pipelined";
  const Json a = run_flock(args, &out1);
  const Json b = run_flock(args, &out2);
  ASSERT_TRUE(a.is_object()) << out1;
  ASSERT_TRUE(b.is_object()) << out2;
  EXPECT_GE(a["coverage"].get<double>(), kFullCoverage) << out1;
  EXPECT_EQ(a["landed"].get<int>(), 5) << out1;
  EXPECT_EQ(a["mission_time_s"], b["mission_time_s"]) << out1 << out2;
  EXPECT_EQ(a["coverage"], b["coverage"]) << out1 << out2;
  for (size_t i = 0; i < a["per_agent"].size(); ++i) {
    EXPECT_EQ(a["per_agent"][i]["energy_mah"], b["per_agent"][i]["energy_mah"]) << i;
    EXPECT_EQ(a["per_agent"][i]["distance_m"], b["per_agent"][i]["distance_m"]) << i;
  }
}

}  // namespace
