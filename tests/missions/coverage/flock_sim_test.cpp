// Whole flocks of the pure agent (thesis chapter 3, FSM of fig. 4.6) over a point-mass model: each
// vehicle tracks its velocity setpoint with a first-order lag, the radio delivers broadcasts to
// every live agent within range one step later, with a seeded loss. No simulator, so these
// scenarios run in a second and pin the algorithm down before it meets physics.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <optional>
#include <random>

#include "agent.hpp"
#include "uavsim/common/angles.hpp"

namespace uavsim::missions::coverage {
namespace {

constexpr double kDt_s = 0.05;
constexpr double kLag_s = 0.4;  // velocity response of a quad in GUIDED
constexpr double kGravity_m_s2 = 9.81;
constexpr double kSurvivorsTol = 1e-3;

struct SimVehicle {
  SimVehicle(Agent a, const Eigen::Vector3d& p) : agent(std::move(a)), position_enu_m(p) {}
  Agent agent;
  Eigen::Vector3d position_enu_m;
  Eigen::Vector3d velocity_enu_m_s = Eigen::Vector3d::Zero();
  Eigen::Vector3d command_enu_m_s = Eigen::Vector3d::Zero();
  double yaw_rad = 0.0, yaw_rate_rad_s = 0.0;
  bool armed = false, alive = true, landing = false;
  // killed by the simulator: the autopilot disarms (and reports "on the ground", as at any disarm),
  // the vehicle falls, the agent program runs on; its pictures count as lost
  bool crashed = false;
  double going_home_since_s = -1.0;
  double takeoff_altitude_m = -1.0;
  std::vector<Frame> inbox;
};

struct FlockRun {
  bool all_done = false;  // every live agent landed
  double mission_time_s = 0.0;
  double survivors_fraction = 0.0;  // coverage held by live agents
  int completed_by = -1;            // the leader whose query found the rectangle covered
  double min_separation_m = 1e9;    // between flying vehicles
  double distance_m = 0.0;          // flown by all
  int rounds = 0;                   // survey rounds (recalls after losses on the way home + 1)
  int takeoffs = 0;                 // take-off commands, re-launches included
  // the widest gap between neighbours along the line (y) while the leader ran a pass over the
  // rectangle: wider than a footprint leaves a sliver between their pictures
  double max_gap_running_m = 0.0;
  int rewinds = 0;  // passes the leader ran again after a loss inside the line
};

struct FlockScenario {
  int agents = 5;
  double loss = 0.0;
  double range_m = 200.0;
  std::vector<std::pair<double, int>> kills;  // (time, agent)
  // (delay, agent): the agent is killed this long after it enters Going Home
  std::vector<std::pair<double, int>> kills_going_home;
  // (height, agent): the simulator kills the agent's vehicle in its landing descent as it passes
  // this height (see SimVehicle::crashed)
  std::vector<std::pair<double, int>> kills_in_descent;
  double timeout_s = 2000.0;
  uint32_t seed = 1;
  double line_spacing_m = 10.0;  // the take-off line
  bool thesis_flocking = false;  // FlockGains::close_gap off: Algorithm 3 as written
  // a perfect ground station (the optimised variant): every second each live agent receives the
  // union of every agent's pictures so far, the dead agents' included (delivered before they died)
  bool station = false;
};

CoverageConfig area() {
  CoverageConfig c;
  c.length_x_m = 150.0;
  c.width_y_m = 100.0;
  return c;
}

// The widest gap between flying neighbours along y.
double widest_gap_m(const std::vector<SimVehicle>& v) {
  std::vector<double> ys;
  for (const SimVehicle& sv : v)
    if (sv.alive && !sv.crashed && sv.position_enu_m.z() > 5.0) ys.push_back(sv.position_enu_m.y());
  std::sort(ys.begin(), ys.end());
  double gap = 0.0;
  for (size_t i = 1; i < ys.size(); ++i) gap = std::max(gap, ys[i] - ys[i - 1]);
  return gap;
}

FlockRun fly(const FlockScenario& s) {
  CoverageConfig config = area();
  config.gains.close_gap = !s.thesis_flocking;
  std::vector<SimVehicle> v;
  for (int i = 0; i < s.agents; ++i) {
    // take-off line along y, 10 m before the rectangle's x = 0 edge
    const Eigen::Vector2d home(-10.0, s.line_spacing_m * i);
    v.emplace_back(Agent(config, i, home), Eigen::Vector3d(home.x(), home.y(), 0.0));
  }
  std::mt19937 rng(s.seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  FlockRun run;
  double t = 0.0;
  size_t next_kill = 0;
  for (; t < s.timeout_s; t += kDt_s) {
    while (next_kill < s.kills.size() && s.kills[next_kill].first <= t)
      v[static_cast<size_t>(s.kills[next_kill++].second)].alive = false;
    for (const auto& [delay, id] : s.kills_going_home) {
      SimVehicle& sv = v[static_cast<size_t>(id)];
      if (sv.going_home_since_s >= 0.0 && t >= sv.going_home_since_s + delay) sv.alive = false;
    }
    for (const auto& [height, id] : s.kills_in_descent) {
      SimVehicle& sv = v[static_cast<size_t>(id)];
      if (sv.landing && !sv.crashed && sv.position_enu_m.z() <= height) {
        sv.crashed = true;
        sv.armed = false;
      }
    }
    // agents step and broadcast
    std::vector<std::pair<size_t, Frame>> air;
    bool done = true;
    std::optional<AreaParts> station_map;
    if (s.station && std::fmod(t + kDt_s / 2, 1.0) < kDt_s) {
      station_map = AreaParts(config.stripe_count());
      for (const SimVehicle& sv : v) station_map->merge(sv.agent.own());
    }
    for (size_t i = 0; i < v.size(); ++i) {
      SimVehicle& sv = v[i];
      if (!sv.alive) continue;
      AgentInputs in;
      in.gcs_map = station_map;
      in.now_s = t;
      in.armed = sv.armed;
      in.on_ground = sv.crashed || sv.position_enu_m.z() <= 0.0;
      in.position_enu_m = sv.position_enu_m;
      in.velocity_enu_m_s = sv.velocity_enu_m_s;
      in.yaw_enu_rad = sv.yaw_rad;
      in.received = std::move(sv.inbox);
      sv.inbox.clear();
      const AgentOutputs out = sv.agent.step(in);
      if (sv.agent.state() == AgentState::kGoingHome && sv.going_home_since_s < 0.0)
        sv.going_home_since_s = t;
      if (out.note.find("line closed after a loss") != std::string::npos) ++run.rewinds;
      if (!out.note.empty() && std::getenv("FLOCK_DEBUG"))
        std::printf("t=%.2f agent %zu: %s\n", t, i, out.note.c_str());
      run.rounds = std::max(run.rounds, sv.agent.round() + 1);
      switch (out.action) {
        case AgentOutputs::Action::kTakeOff:
          ++run.takeoffs;
          sv.landing = false;
          sv.armed = true;
          sv.takeoff_altitude_m = out.takeoff_altitude_m;
          break;
        case AgentOutputs::Action::kVelocity:
          sv.takeoff_altitude_m = -1.0;
          sv.command_enu_m_s = out.velocity_enu_m_s;
          sv.yaw_rate_rad_s = out.yaw_rate_rad_s;
          break;
        case AgentOutputs::Action::kLand:
          sv.landing = true;
          break;
        case AgentOutputs::Action::kNone:
          break;
      }
      for (const Frame& f : out.broadcast) air.emplace_back(i, f);
      // done when every agent has switched its radio off (landed, and every agent it hears too) or
      // failed: a landed agent may still check a loss and take off again
      if (!sv.agent.flock_landed() && sv.agent.state() != AgentState::kFailed && !sv.crashed)
        done = false;
    }
    if (done) {
      run.all_done = true;
      break;
    }
    // radio: to every other live vehicle in range, minus the losses
    for (const auto& [from, f] : air) {
      for (size_t j = 0; j < v.size(); ++j) {
        if (j == from || !v[j].alive) continue;
        if ((v[j].position_enu_m - v[from].position_enu_m).norm() > s.range_m) continue;
        if (u(rng) < s.loss) continue;
        v[j].inbox.push_back(f);
      }
    }
    // point-mass vehicles
    for (SimVehicle& sv : v) {
      if (sv.crashed) {  // unpowered: it falls
        sv.velocity_enu_m_s = {0.0, 0.0,
                               std::min(0.0, sv.velocity_enu_m_s.z()) - kGravity_m_s2 * kDt_s};
        sv.position_enu_m.z() =
            std::max(0.0, sv.position_enu_m.z() + sv.velocity_enu_m_s.z() * kDt_s);
        if (sv.position_enu_m.z() <= 0.0) sv.velocity_enu_m_s.setZero();
        continue;
      }
      if (!sv.alive || !sv.armed) continue;
      Eigen::Vector3d cmd = sv.command_enu_m_s;
      if (sv.takeoff_altitude_m > 0.0)
        cmd = {0.0, 0.0, std::clamp(sv.takeoff_altitude_m - sv.position_enu_m.z(), -2.0, 2.0)};
      if (sv.landing) cmd = {0.0, 0.0, -1.0};
      sv.velocity_enu_m_s += (cmd - sv.velocity_enu_m_s) * (kDt_s / kLag_s);
      run.distance_m += sv.velocity_enu_m_s.head<2>().norm() * kDt_s;
      sv.position_enu_m += sv.velocity_enu_m_s * kDt_s;
      sv.yaw_rad = std::remainder(sv.yaw_rad + sv.yaw_rate_rad_s * kDt_s, 2.0 * common::kPi);
      if (sv.position_enu_m.z() <= 0.0) {
        sv.position_enu_m.z() = 0.0;
        sv.velocity_enu_m_s.setZero();
        if (sv.landing) sv.armed = false;
      }
    }
    for (const SimVehicle& sv : v) {
      const double x = sv.position_enu_m.x();
      if (sv.alive && sv.agent.state() == AgentState::kRunning && x > 0.0 && x < config.length_x_m)
        run.max_gap_running_m = std::max(run.max_gap_running_m, widest_gap_m(v));
    }
    for (size_t i = 0; i < v.size(); ++i) {
      for (size_t j = i + 1; j < v.size(); ++j) {
        if (!v[i].alive || !v[j].alive || v[i].crashed || v[j].crashed ||
            v[i].position_enu_m.z() < 5.0 || v[j].position_enu_m.z() < 5.0)
          continue;
        const double d = (v[i].position_enu_m - v[j].position_enu_m).norm();
        if (d < run.min_separation_m && std::getenv("FLOCK_DEBUG"))
          std::printf("t=%.1f %zu(%s) %zu(%s) %.2f m\n", t, i, agent_state_name(v[i].agent.state()),
                      j, agent_state_name(v[j].agent.state()), d);
        run.min_separation_m = std::min(run.min_separation_m, d);
      }
    }
  }
  run.mission_time_s = t;
  AreaParts held(config.stripe_count());
  for (const SimVehicle& sv : v) {
    if (!sv.alive || sv.crashed) continue;
    held.merge(sv.agent.own());
    if (sv.agent.mission_complete()) run.completed_by = sv.agent.id();
  }
  run.survivors_fraction = held.covered_fraction(config.width_y_m);
  return run;
}

TEST(FlockSim, FiveAgentsCoverTheRectangleAndLand) {
  const FlockRun r = fly({});
  EXPECT_TRUE(r.all_done);
  EXPECT_NEAR(r.survivors_fraction, 1.0, kSurvivorsTol);
  EXPECT_GT(r.min_separation_m, 2.0);
  // 150 x 100 with a ~37 m swath: three or four passes of ~165 m at 5 m/s plus turns
  EXPECT_LT(r.mission_time_s, 600.0);
  std::printf("mission %.1f s, distance %.0f m, min separation %.2f m\n", r.mission_time_s,
              r.distance_m, r.min_separation_m);
}

TEST(FlockSim, PassesRunWithNoTwoNeighboursFurtherApartThanAFootprint) {
  // from a take-off line wider than the formation (15 m apart), the first pass waits for the line
  // to close up (without that wait: 15 m gaps over the first stripes, and 1.3 m between two
  // agents closing up in the pass), and the followers keep it closed on every pass
  FlockScenario s;
  s.line_spacing_m = 15.0;
  const FlockRun r = fly(s);
  EXPECT_TRUE(r.all_done);
  EXPECT_NEAR(r.survivors_fraction, 1.0, kSurvivorsTol);
  EXPECT_GT(r.min_separation_m, 2.0);
  EXPECT_LT(r.max_gap_running_m, area().y_sensor_m) << "mission " << r.mission_time_s << " s";
  std::printf("widest gap in a pass %.2f m, mission %.1f s\n", r.max_gap_running_m,
              r.mission_time_s);
}

TEST(FlockSim, EightAgentsGoHomeInTheirLayersWithoutCrossingAClimbingNeighbour) {
  // from the take-off line of the generated worlds (7 m apart), 8 agents end their last pass in
  // line and go home along it in four layers: the one whose layer is the survey altitude used to
  // set off at once, through the column its neighbour was still climbing (1.27 m apart)
  FlockScenario s;
  s.agents = 8;
  s.line_spacing_m = 7.0;
  const FlockRun r = fly(s);
  EXPECT_TRUE(r.all_done);
  EXPECT_NEAR(r.survivors_fraction, 1.0, kSurvivorsTol);
  EXPECT_GT(r.min_separation_m, 2.0);
  std::printf("min separation %.2f m, mission %.1f s\n", r.min_separation_m, r.mission_time_s);
}

TEST(FlockSim, LeaderKilledANewLeaderFinishes) {
  FlockScenario s;
  s.kills = {{60.0, 0}};
  const FlockRun r = fly(s);
  EXPECT_TRUE(r.all_done);
  EXPECT_EQ(r.completed_by, 1);
  EXPECT_NEAR(r.survivors_fraction, 1.0, kSurvivorsTol);
}

TEST(FlockSim, NonLeaderKilledItsStripesAreCoveredAgain) {
  FlockScenario s;
  s.kills = {{70.0, 3}};
  const FlockRun r = fly(s);
  EXPECT_TRUE(r.all_done);
  EXPECT_NEAR(r.survivors_fraction, 1.0, kSurvivorsTol);
}

// With a ground station, an agent deep inside a line of 12 dies in the first pass: its pictures
// survive, but the strip it leaves open until its neighbours close the gap lies too far from the
// flock's edges for the next pass to bend over it.
// The leader holds the flock until the line has closed, flies back past where the agent died and
// runs that stretch again, instead of sending the whole flock back for it at the end.
TEST(FlockSim, AgentLostDeepInsideTheLineTheLeaderRunsTheStretchAgain) {
  FlockScenario s;
  s.agents = 12;
  s.line_spacing_m = 7.0;
  s.station = true;
  const FlockRun calm = fly(s);
  s.kills = {{30.0, 6}};
  const FlockRun r = fly(s);
  EXPECT_TRUE(r.all_done);
  EXPECT_EQ(r.rewinds, 1);
  EXPECT_NEAR(r.survivors_fraction, 1.0, kSurvivorsTol);
  std::printf("mission %.1f s, without the loss %.1f s\n", r.mission_time_s, calm.mission_time_s);
  // an agent near the edge: the next pass covers its strip, no rewind
  s.kills = {{30.0, 10}};
  EXPECT_EQ(fly(s).rewinds, 0);
  // without the station the dead agent's pictures of the pass are lost and its whole strip is
  // flown again later, the open stretch with it: no rewind
  s.station = false;
  s.kills = {{30.0, 6}};
  EXPECT_EQ(fly(s).rewinds, 0);
}

TEST(FlockSim, ThirtyPercentRadioLossStillCoversEverything) {
  FlockScenario s;
  s.loss = 0.3;
  const FlockRun r = fly(s);
  EXPECT_TRUE(r.all_done);
  EXPECT_NEAR(r.survivors_fraction, 1.0, kSurvivorsTol);
}

TEST(FlockSim, AgentLostOnTheWayHomeTheFlockGoesBackForItsStripes) {
  // without the check, the pictures only agent 3 held die with it after the going-home broadcast
  FlockScenario s;
  s.kills_going_home = {{5.0, 3}};
  const FlockRun r = fly(s);
  EXPECT_TRUE(r.all_done);
  EXPECT_EQ(r.rounds, 2);  // one recall
  EXPECT_NEAR(r.survivors_fraction, 1.0, kSurvivorsTol);
  const FlockRun plain = fly({});
  EXPECT_GT(r.mission_time_s, plain.mission_time_s);  // the extra pass costs time
  std::printf("recall: mission %.1f s (without the loss %.1f s), distance %.0f m (%.0f m)\n",
              r.mission_time_s, plain.mission_time_s, r.distance_m, plain.distance_m);
}

TEST(FlockSim, AgentKilledInItsLandingDescentIsAFailureNotALanding) {
  // the simulator's kill disarms the autopilot, which then reports "on the ground" as at any
  // disarm: taken for a touchdown, the agent would beacon "landed" with pictures that died with it
  FlockScenario s;
  s.kills_in_descent = {{8.0, 3}};
  const FlockRun r = fly(s);
  EXPECT_TRUE(r.all_done);
  EXPECT_EQ(r.rounds, 2);  // the leader, still flying, noticed the loss and recalled the flock
  EXPECT_NEAR(r.survivors_fraction, 1.0, kSurvivorsTol);
}

TEST(FlockSim, LeaderLostOnTheWayHomeTheNextOneChecksAndRecalls) {
  FlockScenario s;
  s.kills_going_home = {{5.0, 0}};
  const FlockRun r = fly(s);
  EXPECT_TRUE(r.all_done);
  EXPECT_EQ(r.rounds, 2);
  EXPECT_NEAR(r.survivors_fraction, 1.0, kSurvivorsTol);
}

TEST(FlockSim, LastFlyerLostAfterTheOthersLandedTheLowestLandedTakesOffAgain) {
  // agent 0 leads and lands last; the simulator kills it in its final descent, after the others
  // have landed: nobody is left flying to notice. The lowest id landed (1) notices it age out,
  // queries the landed agents, finds agent 0's pictures missing, takes off and covers them again
  FlockScenario s;
  s.kills_in_descent = {{2.0, 0}};
  const FlockRun r = fly(s);
  EXPECT_TRUE(r.all_done);
  EXPECT_EQ(r.rounds, 2);
  EXPECT_EQ(r.takeoffs, 6);  // five, and agent 1 again
  EXPECT_NEAR(r.survivors_fraction, 1.0, kSurvivorsTol);
}

}  // namespace
}  // namespace uavsim::missions::coverage
