// Runner pacing on a fake wall clock: time the gate holds the clock (an API pause, a lockstep client
// that takes long or times out) is not caught up afterwards.
#include "sim/runner.hpp"

#include <gtest/gtest.h>

#include "fake_wall_clock.hpp"
#include "sim_fixture.hpp"

namespace uavsim::server::sim {
namespace {

using testing::FakeWallClock;

constexpr double kTolS = 0.05;  // a control step or two of slack
constexpr double kRoundOffTol_s = 1e-9;

TEST(Runner, RealTimePacingFollowsTheWallClock) {
  auto sim = testing::make_sim("empty.xml");
  FakeWallClock clock;
  Runner runner(*sim, 1.0, &clock);
  const double start = clock.now_s();
  runner.run_until(2.0);
  // 2 s of sim time at rate 1 take 2 s of (fake) wall time
  EXPECT_NEAR(clock.now_s() - start, 2.0, kTolS);
}

TEST(Runner, TimeHeldInTheGateIsNotFastForwarded) {
  auto sim = testing::make_sim("empty.xml");
  FakeWallClock clock;
  Runner runner(*sim, 1.0, &clock);
  // the gate holds the clock for 5 s once, at sim time 1 s (as an API pause or a lockstep wait would)
  bool held = false;
  double sim_after_hold = -1.0, wall_after_hold = 0.0;
  runner.add_gate(Phase::kQueuedTasks, "test", [&](double t) {
    if (!held && t >= 1.0) {
      held = true;
      clock.advance(5.0);
      sim_after_hold = t;
      wall_after_hold = clock.now_s();
    }
  });
  runner.run_until(3.0);
  ASSERT_TRUE(held);
  // after the hold the remaining 2 s of sim time take 2 s of wall time, not 0 (the old fast-forward)
  EXPECT_NEAR(clock.now_s() - wall_after_hold, 3.0 - sim_after_hold, kTolS);
}

TEST(Runner, RateChangeReanchorsWithoutAJump) {
  auto sim = testing::make_sim("empty.xml");
  FakeWallClock clock;
  Runner runner(*sim, 1.0, &clock);
  bool changed = false;
  double wall_at_change = 0.0, sim_at_change = 0.0;
  runner.add_gate(Phase::kQueuedTasks, "test", [&](double t) {
    if (!changed && t >= 1.0) {
      changed = true;
      runner.set_rate(4.0);
      wall_at_change = clock.now_s();
      sim_at_change = t;
    }
  });
  runner.run_until(3.0);
  // 2 s of sim time at 4x: 0.5 s of wall time
  EXPECT_NEAR(clock.now_s() - wall_at_change, (3.0 - sim_at_change) / 4.0, kTolS);
}

TEST(Runner, RateZeroTakesNoWallTimeAndStopsOnTheEndTime) {
  // as fast as possible: the runner never sleeps, so the fake wall clock does not move; it ends on
  // the physics step nearest the end time (within half a step)
  auto sim = testing::make_sim("empty.xml");
  FakeWallClock clock;
  Runner runner(*sim, 0.0, &clock);
  const double start = clock.now_s();
  runner.run_until(2.0);
  EXPECT_EQ(clock.now_s(), start);
  EXPECT_NEAR(sim->time_s(), 2.0, 0.5 * sim->physics_dt_s() + kRoundOffTol_s);
}

TEST(Runner, StopFromTheGateEndsTheRunAfterThatStep) {
  // stop() is honoured at the next step: the step the gate opened still runs, no other
  auto sim = testing::make_sim("empty.xml");
  FakeWallClock clock;
  Runner runner(*sim, 0.0, &clock);
  double stopped_at = -1.0;
  runner.add_gate(Phase::kQueuedTasks, "test", [&](double t) {
    if (stopped_at < 0.0 && t >= 1.0) {
      stopped_at = t;
      runner.stop();
    }
  });
  runner.run_until(10.0);
  ASSERT_GE(stopped_at, 1.0);
  EXPECT_NEAR(sim->time_s(), stopped_at + sim->physics_dt_s(), kRoundOffTol_s);
}

}  // namespace
}  // namespace uavsim::server::sim
