// The lockstep contract's core on a fake wall clock: which clients gate the clock, their ticks and
// "done"s, the MAVLink wait, the timeout that drops a dead client, joining and leaving, and (driven
// by the Runner) that wall time the contract held the clock is never fast-forwarded afterwards.
#include "api/lockstep_coordinator.hpp"

#include <gtest/gtest.h>

#include "fake_wall_clock.hpp"
#include "sim/runner.hpp"
#include "sim_fixture.hpp"

namespace uavsim::server::api {
namespace {

using sim::testing::FakeWallClock;

// the server's default rates: physics at 1 kHz, control at 500 Hz (a quarter physics step is the
// tolerance of "the same instant")
constexpr double kControlDt_s = 0.002;
constexpr double kPhysicsDt_s = 0.001;
constexpr double kDefaultTimeout_s = 10.0;
constexpr double kTimeEps_s = 1e-9;

class Lockstep : public ::testing::Test {
 protected:
  FakeWallClock clock_;
  LockstepCoordinator coordinator_{kControlDt_s, kPhysicsDt_s, kDefaultTimeout_s,
                                   [this] { return clock_.now_s(); }};

  // announces every tick due at sim time t; returns the clients ticked
  std::vector<uint64_t> announce(double t) {
    std::vector<uint64_t> due = coordinator_.due(t);
    for (uint64_t conn : due) coordinator_.begin_tick(conn, t);
    return due;
  }
  void done(uint64_t conn, std::optional<double> busy_until_s = std::nullopt,
            std::map<size_t, uint8_t> seq = {}) {
    std::string message;
    ASSERT_EQ(coordinator_.check_done(conn, std::nullopt, &message), std::nullopt) << message;
    coordinator_.take_done(conn, busy_until_s, std::move(seq));
  }
  // conn joins at t = 0 with a 0.1 s period and completes its first tick (at 0) with this done
  void join_and_complete_first_tick(uint64_t conn,
                                    std::optional<double> busy_until_s = std::nullopt) {
    coordinator_.join(conn, 0.1, std::nullopt, 0.0);
    announce(0.0);
    done(conn, busy_until_s);
    coordinator_.complete(nullptr);
  }
};

TEST_F(Lockstep, PeriodIsRoundedToControlStepsAndTicksFallOnItsMultiples) {
  // 0.0101 s = 5.05 control steps of 2 ms -> 5 steps = 0.01 s; joined at 0.013 s the first tick is
  // 0.02
  const auto joined = coordinator_.join(1, 0.0101, std::nullopt, 0.013);
  EXPECT_NEAR(joined.period_s, 0.01, kTimeEps_s);
  EXPECT_NEAR(joined.first_tick_time_s, 0.02, kTimeEps_s);
  EXPECT_EQ(joined.timeout_s, kDefaultTimeout_s);
  EXPECT_TRUE(announce(0.018).empty());
  // a period shorter than a control step is one control step
  EXPECT_NEAR(coordinator_.join(2, 0.0001, 3.0, 0.0).period_s, kControlDt_s, kTimeEps_s);
}

TEST_F(Lockstep, ATickHoldsTheClockUntilItsDone) {
  coordinator_.join(1, 0.1, std::nullopt, 0.0);
  ASSERT_EQ(announce(0.0), std::vector<uint64_t>{1});
  EXPECT_TRUE(coordinator_.blocked());
  // nothing else is due while the tick waits, and completing without a done changes nothing
  EXPECT_TRUE(coordinator_.due(0.0).empty());
  coordinator_.complete(nullptr);
  EXPECT_TRUE(coordinator_.blocked());
  done(1);
  coordinator_.complete(nullptr);
  EXPECT_FALSE(coordinator_.blocked());
  // the next tick is one period on: tick 1 at 0.1 s (sim times a quarter physics step apart are
  // one)
  EXPECT_TRUE(coordinator_.due(0.098).empty());
  ASSERT_EQ(coordinator_.due(0.1 - 0.2 * kPhysicsDt_s), std::vector<uint64_t>{1});
  EXPECT_EQ(coordinator_.begin_tick(1, 0.1), 1);
}

TEST_F(Lockstep, DoneIsRefusedWithoutJoinWithoutATickTwiceAndForAnotherTick) {
  std::string message;
  EXPECT_EQ(coordinator_.check_done(1, std::nullopt, &message), common::ApiError::kNotJoined);
  coordinator_.join(1, 0.1, std::nullopt, 0.0);
  EXPECT_EQ(coordinator_.check_done(1, std::nullopt, &message), common::ApiError::kBadState);
  announce(0.0);
  EXPECT_EQ(coordinator_.check_done(1, 3.0, &message), common::ApiError::kBadField);
  EXPECT_EQ(message, "the tick waiting is 0");
  EXPECT_EQ(coordinator_.check_done(1, 0.0, &message), std::nullopt);
  coordinator_.take_done(1, std::nullopt, {});
  EXPECT_EQ(coordinator_.check_done(1, std::nullopt, &message), common::ApiError::kBadState);
}

TEST_F(Lockstep, TheTickEndsOnlyOnceTheNamedMavlinkMessagesAreHandled) {
  coordinator_.join(1, 0.1, std::nullopt, 0.0);
  announce(0.0);
  done(1, std::nullopt, {{0, 17}, {2, 200}});
  EXPECT_TRUE(coordinator_.waiting_on_seq());
  std::map<size_t, uint8_t> handled;  // vehicle -> last seq handled
  const auto seq_processed = [&](size_t v, uint8_t seq) {
    return handled.count(v) && handled[v] == seq;
  };
  handled[0] = 17;
  coordinator_.complete(seq_processed);
  EXPECT_TRUE(coordinator_.blocked());  // vehicle 2's message is not handled yet
  handled[2] = 200;
  coordinator_.complete(seq_processed);
  EXPECT_FALSE(coordinator_.blocked());
  EXPECT_FALSE(coordinator_.waiting_on_seq());
}

TEST_F(Lockstep, AClientThatDoesNotAnswerIsDroppedAtItsTimeout) {
  coordinator_.join(1, 0.1, 2.0, 0.0);
  announce(0.0);
  const double start = clock_.now_s();
  ASSERT_TRUE(coordinator_.deadline_s());
  EXPECT_DOUBLE_EQ(*coordinator_.deadline_s(), start + 2.0);
  clock_.advance(1.999);
  EXPECT_TRUE(coordinator_.expire(0.0).empty());
  EXPECT_TRUE(coordinator_.blocked());
  clock_.advance(0.001);
  const auto dropped = coordinator_.expire(0.0);
  ASSERT_EQ(dropped.size(), 1u);
  EXPECT_EQ(dropped[0].conn, 1u);
  EXPECT_FALSE(coordinator_.blocked());
  EXPECT_FALSE(coordinator_.joined(1));
  EXPECT_FALSE(coordinator_.deadline_s());
}

TEST_F(Lockstep, ADroppedClientThatComesBackIsToldItWasDropped) {
  coordinator_.join(1, 0.1, 2.0, 0.0);
  announce(0.0);
  clock_.advance(2.0);
  ASSERT_EQ(coordinator_.expire(0.0).size(), 1u);
  std::string message;
  EXPECT_EQ(coordinator_.check_done(1, std::nullopt, &message), common::ApiError::kNotJoined);
  EXPECT_NE(message.find("dropped from the lockstep at sim time 0.000 s"), std::string::npos) << message;
  EXPECT_NE(message.find("timeout of 2 s"), std::string::npos) << message;
  // joined again: an ordinary member; left: an ordinary stranger
  coordinator_.join(1, 0.1, 2.0, 0.0);
  coordinator_.leave(1, 0.0);
  EXPECT_EQ(coordinator_.check_done(1, std::nullopt, &message), common::ApiError::kNotJoined);
  EXPECT_EQ(message, "\"done\" without lockstep_join");
}

TEST_F(Lockstep, ADeadClientIsDroppedWhileTheLiveOneKeepsTicking) {
  coordinator_.join(1, 0.1, 1.0, 0.0);  // answers
  coordinator_.join(2, 0.1, 5.0, 0.0);  // never answers
  EXPECT_EQ(announce(0.0), (std::vector<uint64_t>{1, 2}));
  done(1);
  coordinator_.complete(nullptr);
  EXPECT_TRUE(coordinator_.blocked());  // client 2 still holds tick 0
  // client 1's deadline has no say once it answered: at 1 s of wall time nobody is dropped
  clock_.advance(1.0);
  EXPECT_TRUE(coordinator_.expire(0.0).empty());
  clock_.advance(4.0);
  const auto dropped = coordinator_.expire(0.0);
  ASSERT_EQ(dropped.size(), 1u);
  EXPECT_EQ(dropped[0].conn, 2u);
  EXPECT_FALSE(dropped[0].last_left_at_s);  // client 1 still gates the clock
  EXPECT_EQ(coordinator_.client_count(), 1u);
  EXPECT_EQ(announce(0.1), std::vector<uint64_t>{1});
}

TEST_F(Lockstep, JoiningMidRunAndLeavingWhileAwaited) {
  join_and_complete_first_tick(1);
  // a second client joins at 0.05 s: its first tick is 0.1 s, with client 1's
  coordinator_.join(2, 0.1, std::nullopt, 0.05);
  EXPECT_TRUE(announce(0.05).empty());
  EXPECT_EQ(announce(0.1), (std::vector<uint64_t>{1, 2}));
  // client 2 leaves with its tick awaited: it no longer holds the clock, client 1 does (not the
  // last)
  EXPECT_FALSE(coordinator_.leave(2, 0.1));
  EXPECT_FALSE(coordinator_.joined(2));
  EXPECT_TRUE(coordinator_.blocked());
  done(1);
  coordinator_.complete(nullptr);
  EXPECT_FALSE(coordinator_.blocked());
  EXPECT_FALSE(coordinator_.leave(7, 0.1));  // never joined
}

TEST_F(Lockstep, TheLastClientLeavesAtTheTickTheClockCannotHavePassed) {
  // awaited, no done: the tick it is at
  coordinator_.join(1, 0.1, std::nullopt, 0.0);
  announce(0.3);
  EXPECT_NEAR(*coordinator_.leave(1, 0.3), 0.3, kTimeEps_s);
  // awaited with its done sent (MAVLink pending): that tick counts as completed, so the next one
  coordinator_.join(1, 0.1, std::nullopt, 0.3);
  announce(0.3);
  done(1, std::nullopt, {{0, 5}});
  EXPECT_NEAR(*coordinator_.leave(1, 0.3), 0.4, kTimeEps_s);
  // between ticks: its next tick (the clock may already be past it only if it never got there)
  coordinator_.join(1, 0.1, std::nullopt, 0.31);
  EXPECT_NEAR(*coordinator_.leave(1, 0.32), 0.4, kTimeEps_s);
}

// Two clients end near the same tick: one with its done sent (it leaves at its next tick), one
// without (it leaves at the tick it is at). Whichever disconnect is noticed last, the lockstep is
// empty at the later of the two, so a launcher's run ends at the same sim time every run (before,
// the one noticed last decided: 0.3 s or 0.4 s by wall-clock timing).
TEST_F(Lockstep, TheLockstepEmptiesAtTheLatestLeavingTickWhateverTheOrder) {
  for (const bool done_one_noticed_last : {false, true}) {
    SCOPED_TRACE(done_one_noticed_last ? "done client noticed last" : "done client noticed first");
    coordinator_.reset();
    coordinator_.join(1, 0.1, std::nullopt, 0.3);
    coordinator_.join(2, 0.1, std::nullopt, 0.3);
    EXPECT_EQ(announce(0.3), (std::vector<uint64_t>{1, 2}));
    done(1);  // client 1 answered tick 0.3 s, then exits; client 2 exits before answering
    std::optional<double> empty_at_s;
    if (done_one_noticed_last) {
      EXPECT_FALSE(coordinator_.leave(2, 0.3));
      empty_at_s = coordinator_.leave(1, 0.3);
    } else {
      EXPECT_FALSE(coordinator_.leave(1, 0.3));
      empty_at_s = coordinator_.leave(2, 0.3);
    }
    ASSERT_TRUE(empty_at_s);
    EXPECT_NEAR(*empty_at_s, 0.4, kTimeEps_s);
  }
}

TEST_F(Lockstep, BusyUntilSkipsTicksUpToTheFirstAtOrAfterIt) {
  // detached timing: done at tick 0 with busy_until 0.35 s, period 0.1 s -> next tick 0.4 s
  join_and_complete_first_tick(1, 0.35);
  EXPECT_TRUE(announce(0.3).empty());
  EXPECT_EQ(announce(0.4), std::vector<uint64_t>{1});
}

TEST_F(Lockstep, ResetEndsTheAwaitedTickAndTicksAgainFromZero) {
  join_and_complete_first_tick(1);
  announce(0.1);
  coordinator_.reset();
  EXPECT_FALSE(coordinator_.blocked());
  EXPECT_EQ(announce(0.0), std::vector<uint64_t>{1});
}

// The runner paced at real time on the fake wall clock, its gate holding the clock as ApiServer's
// does: the ticks due, then a wait (sleeping the fake clock) until the clients answer or time out.
class LockstepRunner : public Lockstep {
 protected:
  std::unique_ptr<sim::Simulation> sim_ = sim::testing::make_sim("empty.xml");
  sim::Runner runner_{*sim_, 1.0, &clock_};

  // answer_after_s: wall seconds the client takes for each tick (nullopt: it never answers)
  void hold_with(uint64_t conn, std::optional<double> answer_after_s) {
    runner_.add_gate(sim::Phase::kQueuedTasks, "api", [this, conn, answer_after_s](double t) {
      for (uint64_t c : coordinator_.due(t)) coordinator_.begin_tick(c, t);
      while (coordinator_.blocked()) {
        if (!coordinator_.expire(t).empty()) dropped_at_.push_back({t, clock_.now_s()});
        if (!coordinator_.blocked()) break;
        if (answer_after_s && !coordinator_.check_done(conn, std::nullopt, &message_)) {
          clock_.advance(*answer_after_s);
          coordinator_.take_done(conn, std::nullopt, {});
          coordinator_.complete(nullptr);
          if (t >= leave_at_s_) coordinator_.leave(conn, t);
          continue;
        }
        clock_.sleep_until_s(*coordinator_.deadline_s());
      }
    });
  }

  struct Drop {
    double sim_s, wall_s;
  };
  std::vector<Drop> dropped_at_;
  double leave_at_s_ = 1e9;
  std::string message_;
};

constexpr double kPacingTol_s = 0.05;  // a control step or two of slack

TEST_F(LockstepRunner, AfterADeadClientIsDroppedTheClockGoesOnInRealTimeWithoutCatchingUp) {
  // joined just after t = 0, its first tick is at 0.5 s: that tick is never answered, so 3 s of
  // wall time pass there, then the client is dropped
  coordinator_.join(1, 0.5, 3.0, 0.01);
  hold_with(1, std::nullopt);
  const double start = clock_.now_s();
  runner_.run_until(2.0);
  ASSERT_EQ(dropped_at_.size(), 1u);
  EXPECT_NEAR(dropped_at_[0].sim_s, 0.5, kTimeEps_s);
  // 0.5 s of sim time at real time, then the 3 s hold
  EXPECT_NEAR(dropped_at_[0].wall_s - start, 0.5 + 3.0, kPacingTol_s);
  // the 1.5 s of sim time after the drop take 1.5 s of wall time (the fast-forward of issue 18 ran
  // them as fast as possible, "catching up" the 3 s held)
  EXPECT_NEAR(clock_.now_s() - dropped_at_[0].wall_s, 1.5, kPacingTol_s);
}

TEST_F(LockstepRunner, ASlowClientSlowsTheClockAndWhenItLeavesRealTimeResumesFromThere) {
  // ticks every 0.5 s of sim time, each answered after 0.8 s of wall time: 0.8 s held + 0.5 s run
  coordinator_.join(1, 0.5, std::nullopt, 0.0);
  leave_at_s_ = 1.0;  // answers ticks 0, 0.5 and 1.0, leaving with its done at 1.0
  hold_with(1, 0.8);
  const double start = clock_.now_s();
  runner_.run_until(3.0);
  EXPECT_TRUE(dropped_at_.empty());
  EXPECT_FALSE(coordinator_.joined(1));
  // three holds of 0.8 s and 3 s of sim time paced at real time: 5.4 s
  EXPECT_NEAR(clock_.now_s() - start, 3 * 0.8 + 3.0, kPacingTol_s);
}

}  // namespace
}  // namespace uavsim::server::api
