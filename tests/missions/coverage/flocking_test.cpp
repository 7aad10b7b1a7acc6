// Algorithm 3 (thesis 3.2) with the gains of table 4.1, against hand-computed cases.
#include "flocking.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "uavsim/common/angles.hpp"

namespace uavsim::missions::coverage {
namespace {

constexpr double kTol = 1e-9;
constexpr double kRoundedTol_m_s = 1e-6;  // against a value given to 6 decimals

TEST(Flocking, AngleDiffAndSaturate) {
  EXPECT_NEAR(angle_diff(3.0, -3.0), 6.0 - 2.0 * common::kPi, kTol);  // 6 rad wraps to -0.283
  EXPECT_NEAR(angle_diff(0.1, 0.3), -0.2, kTol);
  EXPECT_EQ(saturate(5.0, 2.0), 2.0);
  EXPECT_EQ(saturate(-5.0, 2.0), -2.0);
  EXPECT_EQ(saturate(1.0, 2.0), 1.0);
}

TEST(Flocking, CohesionMovesOntoTheLineAndTowardsTheLeader) {
  FlockController c{FlockGains{}};
  FlockInputs in;
  in.local_enu_m = {0.0, -10.0};
  in.local_heading_rad = 0.1;
  in.leader_enu_m = {5.0, 0.0};
  in.leader_heading_rad = 0.0;
  in.others_enu_m = {in.leader_enu_m};
  in.dt_s = 0.05;
  const FlockOutputs out = c.step(in);
  // heading 0: parallel = +x, ortho = +y; diff = (5, 10): parallelDiff 5, orthoDiff 10
  // R3x: kp*5 + ki*5*dt = 1.0 + 0.0005*5*0.05 = 1.000125 (under s_R3x = 2)
  EXPECT_FALSE(out.obstructed);
  EXPECT_NEAR(out.parallel_m_s, 1.000125, kTol);
  // nearest agent (the leader) is 10 m across: not under D_R1 = 7.5, so R3y: 0.1 * 10 = 1.0
  EXPECT_FALSE(out.separating);
  EXPECT_NEAR(out.ortho_m_s, 1.0, kTol);
  EXPECT_NEAR(out.velocity_enu_m_s.x(), 1.000125, kTol);
  EXPECT_NEAR(out.velocity_enu_m_s.y(), 1.0, kTol);
  // R2: kp_R2 * ANGDIFF(0, 0.1) = 5 * -0.1 = -0.5 rad/s (under 180 deg/s)
  EXPECT_NEAR(out.yaw_rate_rad_s, -0.5, kTol);
}

TEST(Flocking, SeparationPushesAwayFromTheNearestAgentAcrossTheLine) {
  FlockGains algorithm3;  // as written: R1 alone, even where it pushes towards the leader
  algorithm3.close_gap = false;
  FlockController c{algorithm3};
  FlockInputs in;
  in.local_enu_m = {0.0, 0.0};
  in.leader_enu_m = {0.0, 30.0};
  in.others_enu_m = {{1.0, -3.0}, in.leader_enu_m};
  const FlockOutputs out = c.step(in);
  // nearest: (1, -3); from it to us (-1, 3): parallel -1, ortho 3 (< D_R1)
  // sep = 0.5 * (-1)^2 + 0.6 * (1 - (3 / 7.5)^0.4) = 0.5 + 0.6 * (1 - 0.693145) = 0.684113
  EXPECT_TRUE(out.separating);
  EXPECT_NEAR(out.ortho_m_s, 0.5 + 0.6 * (1.0 - std::pow(0.4, 0.4)), kTol);
  EXPECT_NEAR(out.ortho_m_s, 0.684113, kRoundedTol_m_s);
  // R3x: parallelDiff 0 -> direction +x; (1, -3) is 1 m ahead and 3 m across (< D_R1 / 2):
  // obstructed, no parallel speed
  EXPECT_TRUE(out.obstructed);
  EXPECT_EQ(out.parallel_m_s, 0.0);
}

TEST(Flocking, WhereR1PushesTowardsTheLeaderTheFollowerClosesOnTheNextAgentUpToDR1) {
  // our nearest neighbour 7.4 m behind us across the line, the leader 30 m ahead across it: R1
  // alone would crawl towards the leader at 0.6 * (1 - (7.4 / 7.5)^0.4) = 3 mm/s
  FlockInputs in;
  in.local_enu_m = {0.0, 0.0};
  in.leader_enu_m = {0.0, 30.0};
  in.others_enu_m = {{0.0, -7.4}, in.leader_enu_m};
  FlockGains algorithm3;
  algorithm3.close_gap = false;
  FlockOutputs out = FlockController{algorithm3}.step(in);
  EXPECT_TRUE(out.separating);
  EXPECT_NEAR(out.ortho_m_s, 0.6 * (1.0 - std::pow(7.4 / 7.5, 0.4)), kTol);
  // closing on the next agent that way, the leader 30 m across: 0.5 * (30 - 7.5), capped at
  // s_close_gap (1 m/s)
  out = FlockController{FlockGains{}}.step(in);
  EXPECT_FALSE(out.separating);
  EXPECT_NEAR(out.ortho_m_s, 1.0, kTol);
  // not while the leader flies faster than close_gap_leader_speed (a deploy): R1 alone
  in.leader_velocity_enu_m_s = {0.0, 8.0};
  out = FlockController{FlockGains{}}.step(in);
  EXPECT_TRUE(out.separating);
  EXPECT_NEAR(out.ortho_m_s, 0.6 * (1.0 - std::pow(7.4 / 7.5, 0.4)), kTol);
  in.leader_velocity_enu_m_s = {5.0, 0.0};  // a pass at the cruise speed: closing again
  // an agent 9 m across towards the leader: we close on it at kp_close_gap * (9 - D_R1) = 0.75 m/s
  in.others_enu_m.push_back({1.0, 9.0});
  out = FlockController{FlockGains{}}.step(in);
  EXPECT_FALSE(out.separating);
  EXPECT_NEAR(out.ortho_m_s, 0.5 * (9.0 - 7.5), kTol);
  // 7.45 m across (7.52 m away: the one behind is still the nearest): within D_R1, R1 alone again
  in.others_enu_m.back() = {1.0, 7.45};
  out = FlockController{FlockGains{}}.step(in);
  EXPECT_TRUE(out.separating);
  EXPECT_NEAR(out.ortho_m_s, 0.6 * (1.0 - std::pow(7.4 / 7.5, 0.4)), kTol);
  // where R1 pushes away from the leader, R1 alone (the nearest is 3 m towards the leader)
  in.others_enu_m = {{0.0, 3.0}, in.leader_enu_m};
  out = FlockController{FlockGains{}}.step(in);
  EXPECT_TRUE(out.separating);
  EXPECT_LT(out.ortho_m_s, 0.0);
}

TEST(Flocking, SeparationSaturatesAndKeepsItsSide) {
  FlockController c{FlockGains{}};
  FlockInputs in;
  in.local_enu_m = {0.0, 0.0};
  in.leader_enu_m = {10.0, 0.0};
  in.others_enu_m = {{3.0, 1.0}, in.leader_enu_m};
  const FlockOutputs out = c.step(in);
  // nearest (3, 1): to us (-3, -1), sep = 0.5 * 9 + ... > s_R1: -0.8 (we are on its -y side)
  EXPECT_NEAR(out.ortho_m_s, -0.8, kTol);
  // and it blocks the way to the leader along +x
  EXPECT_TRUE(out.obstructed);
}

TEST(Flocking, R3xIsAPiControllerWithFeedForwardOfTheLeader) {
  FlockController c{FlockGains{}};
  FlockInputs in;
  in.local_enu_m = {0.0, 20.0};
  in.leader_enu_m = {4.0, 0.0};
  in.leader_heading_rad = 0.0;
  in.leader_velocity_enu_m_s = {5.0, 0.0};
  in.others_enu_m = {in.leader_enu_m};
  in.dt_s = 0.1;
  // parallelDiff 4: after 10 steps the integral is 10 * 0.0005 * 4 * 0.1 = 0.002
  FlockOutputs out;
  for (int i = 0; i < 10; ++i) out = c.step(in);
  EXPECT_NEAR(out.parallel_m_s, 0.8 + 0.002, kTol);
  // orthoDiff -20: R3y = sat(0.1 * -20, 2) = -2
  EXPECT_NEAR(out.ortho_m_s, -2.0, kTol);
  EXPECT_NEAR(out.velocity_enu_m_s.x(), 5.0 + 0.802, kTol);
  EXPECT_NEAR(out.velocity_enu_m_s.y(), -2.0, kTol);
}

TEST(Flocking, AxesFollowTheLeadersHeading) {
  FlockController c{FlockGains{}};
  FlockInputs in;
  in.local_enu_m = {0.0, 0.0};
  in.local_heading_rad = common::kPi;
  in.leader_enu_m = {-5.0, 10.0};
  in.leader_heading_rad = common::kPi;  // flying -x: parallel = -x, ortho = -y
  in.others_enu_m = {in.leader_enu_m};
  const FlockOutputs out = c.step(in);
  // diff (-5, 10): parallelDiff = 5, orthoDiff = -10
  EXPECT_NEAR(out.parallel_m_s, 1.0 + 0.0005 * 5 * 0.05, kTol);
  EXPECT_NEAR(out.ortho_m_s, -1.0, kTol);
  // velocity: 1.000125 * (-1, 0) + (-1) * (0, -1) = (-1.000125, 1)
  EXPECT_NEAR(out.velocity_enu_m_s.x(), -1.000125, kTol);
  EXPECT_NEAR(out.velocity_enu_m_s.y(), 1.0, kTol);
}

}  // namespace
}  // namespace uavsim::missions::coverage
