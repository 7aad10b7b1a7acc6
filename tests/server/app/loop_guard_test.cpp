// The watchdog thread: a loop stuck while a stop signal waits is reported, then left (the process
// exits with 128 + signal). That a loop which finished in time is never left is LoopWatchdog's
// decision, tested on a fake clock (tests/server/sim/loop_watchdog_test.cpp).
#include "app/loop_guard.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <csignal>
#include <future>
#include <sstream>

namespace uavsim::server::app {
namespace {

// a bound for waits on the guard's thread: far above its 0.1 s polls on a loaded machine
constexpr auto kWaitBound = std::chrono::seconds(60);

TEST(LoopGuard, ALoopThatIgnoresAStopSignalIsReportedThenLeft) {
  sim::LoopActivity stuck;
  stuck.set_time(3.25);
  stuck.enter("pre_physics/radio");
  sim::WatchdogOptions o;
  o.stall_s = 0.2;  // reported before the grace time ends: both on the guard's one thread
  o.stop_grace_s = 0.6;
  std::ostringstream out;
  std::promise<int> exited;
  LoopGuard guard(
      stuck, o, true, [] { return SIGTERM; }, out, [&](int code) { exited.set_value(code); });
  std::future<int> code = exited.get_future();
  ASSERT_EQ(code.wait_for(kWaitBound), std::future_status::ready);
  EXPECT_EQ(code.get(), 128 + SIGTERM);
  const std::string said = out.str();
  EXPECT_NE(said.find("no progress"), std::string::npos) << said;
  EXPECT_NE(said.find("pre_physics/radio"), std::string::npos) << said;
  EXPECT_NE(said.find("did not stop"), std::string::npos) << said;
  EXPECT_LT(said.find("no progress"), said.find("did not stop")) << said;
  EXPECT_EQ(guard.summary().rfind("1 stall", 0), 0u) << guard.summary();
}

}  // namespace
}  // namespace uavsim::server::app
