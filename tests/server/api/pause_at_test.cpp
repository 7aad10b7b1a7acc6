// pause_at (docs/protocol.md): the clock holds at an armed sim time, and at the tick of the last
// lockstep client when it leaves, whatever the wall-clock timing of its leaving; how the mission
// launchers end their runs at the same sim time every run.
#include <gtest/gtest.h>

#include <memory>

#include "api_fixture.hpp"

namespace uavsim::server::api::testing {
namespace {

constexpr double kHeldTolerance_s =
    0.0021;  // the pause falls on the first control step (2 ms) at or after its time
constexpr int kMaxPolls = 100000;

// polls status until the clock is held; the held time, or -1
double wait_paused(TestClient& c) {
  for (int i = 0; i < kMaxPolls; ++i) {
    const Json s = c.request({{"op", "status"}});
    if (s["result"].value("paused", false)) return s["result"].value("time_s", -1.0);
  }
  return -1.0;
}

TEST(PauseAt, HoldsTheClockAtTheArmedTimesOneAfterTheOther) {
  TestServer server("empty.xml", paused());
  TestClient c(server.port());
  Json r = c.request({{"op", "pause_at"}, {"time_s", 0.5}});
  ASSERT_TRUE(r["ok"]) << r;
  ASSERT_TRUE(c.request({{"op", "pause_at"}, {"time_s", 0.3}})["ok"]);
  ASSERT_TRUE(c.request({{"op", "resume"}})["ok"]);
  EXPECT_NEAR(wait_paused(c), 0.3, kHeldTolerance_s);
  ASSERT_TRUE(c.request({{"op", "resume"}})["ok"]);
  EXPECT_NEAR(wait_paused(c), 0.5, kHeldTolerance_s);
  EXPECT_EQ(error_code(c.request({{"op", "pause_at"}})), "missing_field");
  EXPECT_EQ(error_code(c.request({{"op", "pause_at"}, {"time_s", "soon"}})), "bad_field");
}

// a client that answered its tick at 0.5 s and then disconnects: the clock holds at its next tick,
// 0.6 s, however late the server notices the disconnect
TEST(PauseAt, HoldsAtTheNextTickOfTheLastLockstepClientToLeave) {
  TestServer server("empty.xml", paused());
  TestClient c(server.port());
  auto member = std::make_unique<TestClient>(server.port());
  ASSERT_TRUE(member->request({{"op", "lockstep_join"}, {"period_s", 0.1}})["ok"]);
  ASSERT_TRUE(c.request({{"op", "pause_at"}, {"lockstep_empty", true}})["ok"]);
  ASSERT_TRUE(c.request({{"op", "resume"}})["ok"]);
  for (;;) {
    const Json tick = member->next_event("tick");
    ASSERT_FALSE(tick.is_null());
    ASSERT_TRUE(member->request({{"op", "done"}, {"tick", tick["tick"]}})["ok"]);
    if (tick["time"].get<double>() > 0.45) break;
  }
  member.reset();
  EXPECT_NEAR(wait_paused(c), 0.6, kHeldTolerance_s);
}

}  // namespace
}  // namespace uavsim::server::api::testing
