// The watchdog's decisions on a fake wall clock, and its trail through a real step schedule.
#include "sim/loop_watchdog.hpp"

#include <gtest/gtest.h>

#include "sim/step_schedule.hpp"

namespace uavsim::server::sim {
namespace {

constexpr double kStall_s = 10.0;
constexpr double kGrace_s = 5.0;

WatchdogOptions options() {
  WatchdogOptions o;
  o.stall_s = kStall_s;
  o.stop_grace_s = kGrace_s;
  return o;
}

TEST(LoopWatchdog, AMovingLoopIsNeverAStall) {
  LoopActivity a;
  LoopWatchdog w(a, options());
  for (int i = 0; i < 1000; ++i) {
    a.beat();
    EXPECT_FALSE(w.poll(0.1 * i)) << i;
  }
  EXPECT_EQ(w.stalls(), 0u);
}

TEST(LoopWatchdog, AStuckLoopIsReportedOnceWithWhereItIsThenItsRecovery) {
  LoopActivity a;
  a.set_time(12.5);
  a.enter("pre_physics/radio");
  a.set_detail("radio_send");
  LoopWatchdog w(a, options());
  EXPECT_FALSE(w.poll(100.0));  // first look
  EXPECT_FALSE(w.poll(100.0 + kStall_s - 0.1));
  const auto stall = w.poll(100.0 + kStall_s);
  ASSERT_TRUE(stall);
  EXPECT_DOUBLE_EQ(stall->for_s, kStall_s);
  EXPECT_DOUBLE_EQ(stall->time_s, 12.5);
  EXPECT_EQ(stall->where, "pre_physics/radio: radio_send");
  EXPECT_FALSE(w.poll(100.0 + 3 * kStall_s));  // once per stall
  EXPECT_FALSE(w.take_recovery());
  a.beat();
  EXPECT_FALSE(w.poll(100.0 + 4 * kStall_s));
  const auto lasted = w.take_recovery();
  ASSERT_TRUE(lasted);
  EXPECT_DOUBLE_EQ(*lasted, 4 * kStall_s);
  EXPECT_FALSE(w.take_recovery());
  EXPECT_EQ(w.stalls(), 1u);
  EXPECT_DOUBLE_EQ(w.longest_stall_s(), 4 * kStall_s);
}

TEST(LoopWatchdog, AStopTheLoopIgnoresForTheGraceTimeMeansExit) {
  LoopActivity a;
  LoopWatchdog w(a, options());
  EXPECT_FALSE(w.must_exit(50.0));  // no stop asked
  w.stop_requested(50.0);
  w.stop_requested(53.0);  // the first request counts
  EXPECT_FALSE(w.must_exit(50.0 + kGrace_s - 0.1));
  EXPECT_TRUE(w.must_exit(50.0 + kGrace_s));
  // a loop that finished in time is not forced
  w.loop_finished();
  EXPECT_FALSE(w.must_exit(1000.0));
}

TEST(LoopWatchdog, TheScheduleLeavesATrailOfItsEntries) {
  StepSchedule schedule;
  LoopActivity& a = schedule.activity();
  std::string seen_in_api;
  schedule.add(Phase::kQueuedTasks, "api", [&] { seen_in_api = a.where(); });
  schedule.add(Phase::kPostControl, "reporter", [] {});
  const uint64_t before = a.progress();
  schedule.run_step(true);
  EXPECT_EQ(seen_in_api, "queued_tasks/api");
  EXPECT_EQ(a.where(), "post_control/reporter");
  EXPECT_EQ(a.progress(), before + 2);
  // entries registered later keep the earlier ones' names readable (the watchdog reads them from
  // another thread)
  for (int i = 0; i < 100; ++i) schedule.add(Phase::kPrePhysics, "late" + std::to_string(i), [] {});
  schedule.run_step(false);
  EXPECT_EQ(a.where(), "pre_physics/late99");
}

}  // namespace
}  // namespace uavsim::server::sim
