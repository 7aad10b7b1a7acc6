// The lockstep contract (seed 5.3/6.5, gzuav's Begin-Tick/End-Tick): ticks at multiples of each
// client's period, the clock held until every joined client is done, busy_until, MAVLink seq waits
// and the dead-client timeout — on both transports: every test runs with its lockstep clients
// reading over TCP and over the shared-memory stream (docs/protocol.md), the contract the same on
// both.
#include <gtest/gtest.h>
#include <poll.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <map>
#include <ostream>
#include <thread>

#include "api/api_server.hpp"
#include "api_fixture.hpp"

namespace uavsim::server::api {
namespace {

using testing::Json;
using testing::TestClient;
using testing::TestServer;

constexpr double kEndTime_s = 0.3;
constexpr double kTimeTol_s = 1e-9;

enum class Transport { kTcp, kShm };
void PrintTo(Transport t, std::ostream* os) { *os << (t == Transport::kTcp ? "tcp" : "shm"); }

class LockstepContract : public ::testing::TestWithParam<Transport> {
 protected:
  // A lockstep client as this test's transport has it read: on shared memory from before its join.
  static void choose_transport(TestClient& c) {
    if (GetParam() == Transport::kShm) ASSERT_TRUE(c.use_shared_memory());
  }
};

std::string error_code_of(const Json& reply) {
  return reply.value("ok", true) ? "" : reply["error"].value("code", "");
}

struct LockstepRun {
  std::vector<double> ticks_a, ticks_b;
  std::vector<std::pair<std::string, double>> events;
};

// client A (period 10 ms) fails a motor of uav0 at its tick 5; client B (period 20 ms) declares itself busy
// for 100 ms at its tick 2 (detached timing) and kills uav1 at its tick 10
LockstepRun run_scenario(Transport transport) {
  ApiConfig config;
  config.start_paused = true;
  TestServer server("mbzirc2020.xml", config);
  TestClient control(server.port());
  LockstepRun run;
  auto client = [&](double period, std::vector<double>* ticks, auto on_tick) {
    return std::thread([&, period, ticks, on_tick] {
      TestClient c(server.port());
      if (transport == Transport::kShm) ASSERT_TRUE(c.use_shared_memory());
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

TEST_P(LockstepContract, TwoClientsGiveIdenticalRunsAndEventsAtTheirTicks) {
  const LockstepRun first = run_scenario(GetParam());
  const LockstepRun second = run_scenario(GetParam());
  EXPECT_EQ(first.ticks_a, second.ticks_a);
  EXPECT_EQ(first.ticks_b, second.ticks_b);
  EXPECT_EQ(first.events, second.events);
  // A ticked every 10 ms from 0
  ASSERT_EQ(first.ticks_a.size(), 31u);
  for (size_t i = 0; i < first.ticks_a.size(); ++i)
    EXPECT_NEAR(first.ticks_a[i], 0.01 * i, kTimeTol_s);
  // the commands took effect exactly at the ticks they were sent in: A's tick 5, B's tick 10
  std::map<std::string, double> at;
  for (const auto& [type, time] : first.events) {
    at.emplace(type, time);
  }
  ASSERT_TRUE(at.count("motor_failure"));
  EXPECT_NEAR(at["motor_failure"], 0.05, kTimeTol_s);
  ASSERT_TRUE(at.count("vehicle_killed"));
  EXPECT_NEAR(at["vehicle_killed"], 0.20, kTimeTol_s);
}

TEST_P(LockstepContract, BusyUntilSkipsTheClientsTicksUntilThatTime) {
  const LockstepRun run = run_scenario(GetParam());
  // B: 0, 0.02, 0.04 (busy until 0.14), then 0.14, 0.16, ...
  const std::vector<double> expected = {0.0, 0.02, 0.04, 0.14, 0.16, 0.18, 0.20, 0.22, 0.24, 0.26, 0.28, 0.30};
  ASSERT_EQ(run.ticks_b.size(), expected.size());
  for (size_t i = 0; i < expected.size(); ++i)
    EXPECT_NEAR(run.ticks_b[i], expected[i], kTimeTol_s) << i;
}

TEST_P(LockstepContract, ADeadClientIsDroppedAfterTheTimeoutAndTheClockGoesOn) {
  ApiConfig config;
  config.lockstep_timeout_s = 0.2;  // wall clock
  TestServer server("empty.xml", config);
  TestClient dead(server.port()), observer(server.port());
  choose_transport(dead);
  ASSERT_TRUE(dead.request({{"op", "lockstep_join"}, {"period_s", 0.01}})["ok"]);
  const Json tick = dead.next_event("tick");
  ASSERT_FALSE(tick.is_null());
  // held at the tick: other clients are still served, and time does not move
  const double held = observer.request({{"op", "status"}})["result"]["time_s"];
  EXPECT_NEAR(held, tick["time"].get<double>(), kTimeTol_s);
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

// A real process on the lockstep, stopped (SIGSTOP) for longer than its timeout: the server drops
// it and the clock goes on; continued (SIGCONT), its next "done" is told that it was dropped. The
// client is forked before the server starts (no threads to copy) and reports through a pipe.
TEST_P(LockstepContract, AClientStoppedLongerThanItsTimeoutIsDroppedAndToldSoWhenItComesBack) {
  constexpr double kTimeout_s = 0.3;  // wall clock
  int to_child[2], from_child[2];
  ASSERT_EQ(pipe(to_child), 0);
  ASSERT_EQ(pipe(from_child), 0);
  const bool shm = GetParam() == Transport::kShm;
  const pid_t child = fork();
  if (child == 0) {
    prctl(PR_SET_PDEATHSIG, SIGKILL);  // never outlives the test
    close(to_child[1]);
    close(from_child[0]);
    uint16_t port = 0;
    if (read(to_child[0], &port, sizeof(port)) != sizeof(port)) _exit(2);
    TestClient c(port);
    if (shm && !c.use_shared_memory()) _exit(4);
    if (!c.request({{"op", "lockstep_join"}, {"period_s", 0.01}, {"timeout_s", kTimeout_s}})["ok"]) _exit(3);
    (void)!write(from_child[1], "j", 1);
    for (;;) {
      const Json t = c.next_event("tick");
      if (t.is_null()) continue;
      const Json r = c.request({{"op", "done"}, {"tick", t["tick"]}});
      if (!r.value("ok", false)) {
        const std::string m = r["error"].value("message", "") + "|" + r["error"].value("code", "");
        (void)!write(from_child[1], m.data(), m.size());
        _exit(0);
      }
    }
  }
  close(to_child[0]);
  close(from_child[1]);
  struct Reaper {  // whatever happens below, the child does not outlive the test
    pid_t pid;
    ~Reaper() {
      if (pid > 0 && waitpid(pid, nullptr, WNOHANG) == 0) {
        kill(pid, SIGKILL);
        waitpid(pid, nullptr, 0);
      }
    }
  } reaper{child};
  ApiConfig config;
  TestServer server("empty.xml", config);
  TestClient observer(server.port());
  const uint16_t port = server.port();
  ASSERT_EQ(write(to_child[1], &port, sizeof(port)), static_cast<ssize_t>(sizeof(port)));
  char joined = 0;
  ASSERT_EQ(read(from_child[0], &joined, 1), 1);
  auto status = [&] { return observer.request({{"op", "status"}})["result"]; };
  // bounded polls: the bound only turns a hang into a failure
  auto wait_for = [&](auto pred) {
    const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(60);
    while (!pred() && std::chrono::steady_clock::now() < end) usleep(5000);
    return pred();
  };
  ASSERT_TRUE(wait_for([&] { return status()["time_s"].get<double>() > 0.05; }));  // it ticks
  ASSERT_EQ(kill(child, SIGSTOP), 0);
  // dropped after its timeout; the world goes on without it
  ASSERT_TRUE(wait_for([&] { return status()["lockstep_clients"].get<int>() == 0; })) << status();
  const double after_drop_s = status()["time_s"];
  ASSERT_TRUE(wait_for([&] { return status()["time_s"].get<double>() > after_drop_s + 0.1; }));
  ASSERT_EQ(kill(child, SIGCONT), 0);
  std::string told;
  pollfd p{from_child[0], POLLIN, 0};
  char buf[512];
  while (::poll(&p, 1, 60000) > 0) {
    const ssize_t n = read(from_child[0], buf, sizeof(buf));
    if (n <= 0) break;
    told.append(buf, static_cast<size_t>(n));
  }
  int child_status = 0;
  ASSERT_EQ(waitpid(child, &child_status, 0), child);
  reaper.pid = -1;
  EXPECT_TRUE(WIFEXITED(child_status) && WEXITSTATUS(child_status) == 0) << child_status;
  EXPECT_NE(told.find("dropped from the lockstep"), std::string::npos) << told;
  EXPECT_NE(told.find("lockstep_join to take part again|not_joined"), std::string::npos) << told;
  close(to_child[1]);
  close(from_child[0]);
}

// the endpoint's side of the MAVLink race: "done" names a sequence number that is not handled yet
class FakeSeqWaiter : public SeqWaiter {
 public:
  bool seq_processed(size_t vehicle, uint8_t seq) const override {
    return vehicle == 0 && processed.load() >= seq;
  }
  std::atomic<int> processed{-1};
};

TEST_P(LockstepContract, DoneWaitsForTheNamedMavlinkSequenceNumber) {
  FakeSeqWaiter waiter;
  ApiConfig config;
  config.start_paused = false;
  TestServer server("empty.xml", config, nullptr, &waiter);
  TestClient c(server.port()), observer(server.port());
  choose_transport(c);
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
  EXPECT_NEAR(next["time"].get<double>(), tick["time"].get<double>() + 0.01, kTimeTol_s);
  EXPECT_EQ(error_code_of(c.request({{"op", "done"}, {"mavlink_seq", {{"uav7", 1}}}})), "unknown_vehicle");
}

// with_tick: the queries a client joined with come answered just before each of its ticks, at the
// tick's time, in one tick_results message; a query that fails there says why in its own slot;
// leaving ends them.
TEST_P(LockstepContract, QueriesJoinedWithTheTickComeAnsweredJustBeforeEachTick) {
  ApiConfig config;
  config.start_paused = false;
  TestServer server("mbzirc2017.xml", config);
  TestClient c(server.port());
  choose_transport(c);
  // the third fails at every tick: a gimbal query names its gimbal
  const Json join = c.request(
      {{"op", "lockstep_join"},
       {"period_s", 0.02},
       {"with_tick", {{{"op", "status"}}, {{"op", "vehicles"}}, {{"op", "gimbal"}}}}});
  ASSERT_TRUE(join["ok"]) << join;
  for (int i = 0; i < 5; ++i) {
    const Json results = c.read_message();
    ASSERT_EQ(results.value("event", ""), "tick_results") << results;
    const Json tick = c.read_message();  // the tick itself, right behind them
    ASSERT_EQ(tick.value("event", ""), "tick") << tick;
    const double t = tick["time"].get<double>();
    EXPECT_EQ(results["time"].get<double>(), t);
    ASSERT_EQ(results["results"].size(), 3u) << results;
    EXPECT_EQ(results["results"][0]["result"]["time_s"].get<double>(), t) << results;
    EXPECT_EQ(results["results"][1]["result"]["time_s"].get<double>(), t) << results;
    EXPECT_EQ(results["results"][1]["result"]["vehicles"][0]["name"], "uav0") << results;
    EXPECT_EQ(results["results"][2]["error"]["code"], "missing_field") << results;
    ASSERT_TRUE(c.request({{"op", "done"}, {"tick", tick["tick"]}})["ok"]);
  }
  // joined again without: plain ticks
  ASSERT_TRUE(c.request({{"op", "lockstep_leave"}})["ok"]);
  const Json rejoin = c.request({{"op", "lockstep_join"}, {"period_s", 0.02}});
  ASSERT_TRUE(rejoin["ok"]) << rejoin;
  // the first tick of the new membership (the tick after the last done, and its results, may have
  // been sent before the leave: skipped)
  Json first;
  do {
    first = c.next_event("tick");
    ASSERT_FALSE(first.is_null());
  } while (first["time"].get<double>() <
           rejoin["result"]["first_tick_time"].get<double>() - kTimeTol_s);
  ASSERT_TRUE(c.request({{"op", "done"}, {"tick", first["tick"]}})["ok"]);
  const Json second = c.read_message();
  EXPECT_EQ(second.value("event", ""), "tick") << second;
}

TEST_P(LockstepContract, WithTickTakesOnlyAFewQueriesThatReadTheWorld) {
  ApiConfig config;
  config.start_paused = true;
  TestServer server("empty.xml", config);
  TestClient c(server.port());
  choose_transport(c);
  const Json status = {{"op", "status"}};
  for (const Json& bad : {Json("status"), Json::object(), Json::array({Json("status")}),
                          Json::array({Json{{"op", "pause"}}}), Json::array({Json{{"op", 3}}}),
                          Json::array({Json{{"op", "kill_vehicle"}, {"vehicle", 0}}}),
                          Json(std::vector<Json>(9, status))}) {
    const Json r = c.request({{"op", "lockstep_join"}, {"period_s", 0.02}, {"with_tick", bad}});
    EXPECT_EQ(error_code_of(r), "bad_field") << bad;
  }
  // refused: not joined (a done has no tick)
  EXPECT_EQ(error_code_of(c.request({{"op", "done"}})), "not_joined");
  EXPECT_TRUE(c.request({{"op", "lockstep_join"},
                         {"period_s", 0.02},
                         {"with_tick", std::vector<Json>(8, status)}})["ok"]);
}

INSTANTIATE_TEST_SUITE_P(Transports, LockstepContract,
                         ::testing::Values(Transport::kTcp, Transport::kShm),
                         [](const ::testing::TestParamInfo<Transport>& info) {
                           return info.param == Transport::kTcp ? "tcp" : "shm";
                         });

}  // namespace
}  // namespace uavsim::server::api
