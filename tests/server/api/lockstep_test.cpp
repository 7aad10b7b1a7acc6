// The lockstep contract (seed 5.3/6.5, gzuav's Begin-Tick/End-Tick): ticks at multiples of each
// client's period, the clock held until every joined client is done, busy_until, MAVLink seq waits and
// the dead-client timeout.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <map>
#include <thread>

#include "api/api_server.hpp"
#include "api_fixture.hpp"

namespace uavsim::server::api {
namespace {

using testing::Json;
using testing::TestClient;
using testing::TestServer;

constexpr double kEndTime_s = 0.3;

std::string error_code_of(const Json& reply) {
  return reply.value("ok", true) ? "" : reply["error"].value("code", "");
}

struct LockstepRun {
  std::vector<double> ticks_a, ticks_b;
  std::vector<std::pair<std::string, double>> events;
};

// client A (period 10 ms) fails a motor of uav0 at its tick 5; client B (period 20 ms) declares itself busy
// for 100 ms at its tick 2 (detached timing) and kills uav1 at its tick 10
LockstepRun run_scenario() {
  ApiConfig config;
  config.start_paused = true;
  TestServer server("mbzirc2020.xml", config);
  TestClient control(server.port());
  LockstepRun run;
  auto client = [&](double period, std::vector<double>* ticks, auto on_tick) {
    return std::thread([&, period, ticks, on_tick] {
      TestClient c(server.port());
      const Json j = c.request({{"op", "lockstep_join"}, {"period_s", period}});
      ASSERT_TRUE(j["ok"]) << j;
      for (;;) {
        const Json t = c.next_event("tick");
        ASSERT_FALSE(t.is_null()) << "no tick";
        const double time = t["time"];
        if (time > kEndTime_s + 1e-6) {
          c.request({{"op", "lockstep_leave"}});
          return;
        }
        ticks->push_back(time);
        Json done = {{"op", "done"}, {"tick", t["tick"]}};
        on_tick(c, t["tick"].get<int64_t>(), &done);
        const Json r = c.request(done);
        ASSERT_TRUE(r["ok"]) << r;
      }
    });
  };
  std::thread a = client(0.01, &run.ticks_a, [](TestClient& c, int64_t tick, Json*) {
    if (tick == 5) {
      const Json r = c.request({{"op", "motor_failure"}, {"vehicle", 0}, {"rotor", 1}});
      EXPECT_TRUE(r["ok"]) << r;
    }
  });
  std::thread b = client(0.02, &run.ticks_b, [](TestClient& c, int64_t tick, Json* done) {
    if (tick == 2) (*done)["busy_until"] = 0.14;
    if (tick == 10) c.request({{"op", "kill_vehicle"}, {"vehicle", 1}});
  });
  // both joined (lockstep_clients == 2) before the clock starts
  while (control.request({{"op", "status"}})["result"]["lockstep_clients"] != 2) std::this_thread::yield();
  control.request({{"op", "resume"}});
  a.join();
  b.join();
  control.request({{"op", "pause"}});
  const Json ev = control.request({{"op", "events"}});
  for (const Json& e : ev["result"]["events"]) {
    run.events.emplace_back(e["type"].get<std::string>(), e["time"].get<double>());
  }
  return run;
}

TEST(Lockstep, TwoClientsGiveIdenticalRunsAndEventsAtTheirTicks) {
  const LockstepRun first = run_scenario();
  const LockstepRun second = run_scenario();
  EXPECT_EQ(first.ticks_a, second.ticks_a);
  EXPECT_EQ(first.ticks_b, second.ticks_b);
  EXPECT_EQ(first.events, second.events);
  // A ticked every 10 ms from 0
  ASSERT_EQ(first.ticks_a.size(), 31u);
  for (size_t i = 0; i < first.ticks_a.size(); ++i) EXPECT_NEAR(first.ticks_a[i], 0.01 * i, 1e-9);
  // the commands took effect exactly at the ticks they were sent in: A's tick 5, B's tick 10
  std::map<std::string, double> at;
  for (const auto& [type, time] : first.events) {
    at.emplace(type, time);
  }
  ASSERT_TRUE(at.count("motor_failure"));
  EXPECT_NEAR(at["motor_failure"], 0.05, 1e-9);
  ASSERT_TRUE(at.count("vehicle_killed"));
  EXPECT_NEAR(at["vehicle_killed"], 0.20, 1e-9);
}

TEST(Lockstep, BusyUntilSkipsTheClientsTicksUntilThatTime) {
  const LockstepRun run = run_scenario();
  // B: 0, 0.02, 0.04 (busy until 0.14), then 0.14, 0.16, ...
  const std::vector<double> expected = {0.0, 0.02, 0.04, 0.14, 0.16, 0.18, 0.20, 0.22, 0.24, 0.26, 0.28, 0.30};
  ASSERT_EQ(run.ticks_b.size(), expected.size());
  for (size_t i = 0; i < expected.size(); ++i) EXPECT_NEAR(run.ticks_b[i], expected[i], 1e-9) << i;
}

TEST(Lockstep, ADeadClientIsDroppedAfterTheTimeoutAndTheClockGoesOn) {
  ApiConfig config;
  config.lockstep_timeout_s = 0.2;  // wall clock
  TestServer server("empty.xml", config);
  TestClient dead(server.port()), observer(server.port());
  ASSERT_TRUE(dead.request({{"op", "lockstep_join"}, {"period_s", 0.01}})["ok"]);
  const Json tick = dead.next_event("tick");
  ASSERT_FALSE(tick.is_null());
  // held at the tick: other clients are still served, and time does not move
  const double held = observer.request({{"op", "status"}})["result"]["time_s"];
  EXPECT_NEAR(held, tick["time"].get<double>(), 1e-9);
  EXPECT_EQ(observer.request({{"op", "status"}})["result"]["time_s"], held);
  // the dead client is dropped, then the clock runs again
  const Json dropped = dead.next_event("lockstep_dropped");
  ASSERT_FALSE(dropped.is_null());
  EXPECT_EQ(dropped["reason"], "timeout");
  double t = held;
  for (int i = 0; i < 1000 && t <= held + 0.1; ++i) t = observer.request({{"op", "status"}})["result"]["time_s"];
  EXPECT_GT(t, held + 0.1);
  EXPECT_EQ(error_code_of(dead.request({{"op", "done"}})), "not_joined");
}

// the endpoint's side of the MAVLink race: "done" names a sequence number that is not handled yet
class FakeSeqWaiter : public SeqWaiter {
 public:
  bool seq_processed(size_t vehicle, uint8_t seq) const override {
    return vehicle == 0 && processed.load() >= seq;
  }
  std::atomic<int> processed{-1};
};

TEST(Lockstep, DoneWaitsForTheNamedMavlinkSequenceNumber) {
  FakeSeqWaiter waiter;
  ApiConfig config;
  config.start_paused = false;
  TestServer server("empty.xml", config, nullptr, &waiter);
  TestClient c(server.port()), observer(server.port());
  ASSERT_TRUE(c.request({{"op", "lockstep_join"}, {"period_s", 0.01}})["ok"]);
  const Json tick = c.next_event("tick");
  const Json r = c.request({{"op", "done"}, {"tick", tick["tick"]}, {"mavlink_seq", {{"0", 7}}}});
  ASSERT_TRUE(r["ok"]) << r;
  EXPECT_EQ(r["result"]["mavlink_seq_checked"], true);
  // not processed yet: the tick stays open
  for (int i = 0; i < 20; ++i) {
    EXPECT_EQ(observer.request({{"op", "status"}})["result"]["time_s"], tick["time"]);
  }
  waiter.processed = 7;
  const Json next = c.next_event("tick");
  ASSERT_FALSE(next.is_null());
  EXPECT_NEAR(next["time"].get<double>(), tick["time"].get<double>() + 0.01, 1e-9);
  EXPECT_EQ(error_code_of(c.request({{"op", "done"}, {"mavlink_seq", {{"uav7", 1}}}})), "unknown_vehicle");
}

}  // namespace
}  // namespace uavsim::server::api
