#include "api/api_server.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <string>

#include "api_fixture.hpp"
#include "sim/events.hpp"

namespace uavsim::server::api {
namespace {

using testing::error_code;
using testing::Json;
using testing::paused;
using testing::RawClient;
using testing::TestClient;
using testing::TestServer;

constexpr double kControlDt_s = 0.002;  // 500 Hz control
constexpr double kTimeTol_s = 1e-9;
constexpr double kStepTimeTol_s = 1e-6;
constexpr double kStartPosTol_m = 0.05;
constexpr double kHeightTol_m = 1e-9;
constexpr double kAngleTol_deg = 1e-9;

TEST(Api, HelloNamesTheProtocolVersionAndStatusAnswers) {
  TestServer server("mbzirc2020.xml", paused());
  RawClient c(server.port());  // the wire itself: the id is echoed
  EXPECT_EQ(c.hello()["protocol"], 1);
  EXPECT_EQ(c.hello()["hello"], "uavsim");
  const Json r = c.request({{"op", "status"}, {"id", 1}});
  ASSERT_TRUE(r["ok"]) << r;
  EXPECT_EQ(r["id"], 1);
  EXPECT_EQ(r["result"]["vehicles"], 2);
  EXPECT_EQ(r["result"]["paused"], true);
  EXPECT_EQ(r["result"]["protocol"], 1);
  EXPECT_NEAR(r["result"]["time_s"].get<double>(), 0.0, kTimeTol_s);
}

TEST(Api, StepAdvancesWholeControlStepsWhilePausedAndResumeRuns) {
  TestServer server("mbzirc2020.xml", paused());
  TestClient c(server.port());
  Json r = c.request({{"op", "step"}, {"steps", 5}});
  ASSERT_TRUE(r["ok"]) << r;
  EXPECT_NEAR(r["result"]["time_s"].get<double>(), 5 * kControlDt_s, kTimeTol_s);
  r = c.request({{"op", "step"}, {"duration_s", 0.1}});
  EXPECT_NEAR(r["result"]["time_s"].get<double>(), 0.11, kStepTimeTol_s);
  // still paused: time does not move
  EXPECT_NEAR(c.request({{"op", "status"}})["result"]["time_s"].get<double>(), 0.11,
              kStepTimeTol_s);
  EXPECT_EQ(error_code(c.request({{"op", "step"}, {"steps", 0}})), "bad_field");
  EXPECT_EQ(error_code(c.request({{"op", "step"}, {"steps", 1.5}})), "bad_field");
  ASSERT_TRUE(c.request({{"op", "resume"}})["ok"]);
  double t = 0.0;
  for (int i = 0; i < 1000 && t <= 0.2; ++i) t = c.request({{"op", "status"}})["result"]["time_s"];
  EXPECT_GT(t, 0.2);
  const Json p = c.request({{"op", "pause"}});
  const double held = p["result"]["time_s"];
  EXPECT_NEAR(c.request({{"op", "status"}})["result"]["time_s"].get<double>(), held, kTimeTol_s);
}

TEST(Api, SetRateValidatesItsArgument) {
  TestServer server("empty.xml", paused());
  TestClient c(server.port());
  EXPECT_TRUE(c.request({{"op", "set_rate"}, {"rate", 0}})["ok"]);
  EXPECT_EQ(c.request({{"op", "status"}})["result"]["rate"], 0.0);
  EXPECT_EQ(error_code(c.request({{"op", "set_rate"}, {"rate", -1}})), "bad_field");
  EXPECT_EQ(error_code(c.request({{"op", "set_rate"}})), "missing_field");
  // present, of the wrong type
  EXPECT_EQ(error_code(c.request({{"op", "set_rate"}, {"rate", "fast"}})), "bad_field");
}

TEST(Api, ResetGoesBackToTimeZeroWithTheNewSeed) {
  TestServer server("mbzirc2020.xml", paused());
  TestClient c(server.port());
  const Json before = c.request({{"op", "balloons"}})["result"]["balloons"];
  c.request({{"op", "step"}, {"steps", 50}});
  c.request({{"op", "kill_vehicle"}, {"vehicle", 0}});
  const Json r = c.request({{"op", "reset"}, {"seed", 9}});
  ASSERT_TRUE(r["ok"]) << r;
  const Json s = c.request({{"op", "status"}})["result"];
  EXPECT_NEAR(s["time_s"].get<double>(), 0.0, kTimeTol_s);
  EXPECT_EQ(s["seed"], 9);
  EXPECT_EQ(s["events"], 0);
  EXPECT_EQ(c.request({{"op", "vehicles"}})["result"]["vehicles"][0]["crashed"], false);
  // seed 9 draws other balloon positions than seed 1
  EXPECT_NE(c.request({{"op", "balloons"}})["result"]["balloons"][0]["position_enu_m"],
            before[0]["position_enu_m"]);
  EXPECT_EQ(error_code(c.request({{"op", "reset"}, {"seed", -3}})), "bad_field");
}

TEST(Api, WorldQueriesReturnGroundTruth) {
  TestServer server("mbzirc2017.xml", paused());
  TestClient c(server.port());
  c.request({{"op", "step"}, {"steps", 500}});  // 1 s: the truck has driven 4.17 m
  const Json v = c.request({{"op", "vehicles"}})["result"]["vehicles"];
  ASSERT_EQ(v.size(), 1u);
  EXPECT_EQ(v[0]["name"], "uav0");
  EXPECT_EQ(v[0]["frame"], "hexa");
  EXPECT_NEAR(v[0]["position_enu_m"][0].get<double>(), -40.0, kStartPosTol_m);
  EXPECT_EQ(v[0]["q_enu_body"].size(), 4u);
  const Json t = c.request({{"op", "truck"}})["result"]["trucks"][0];
  EXPECT_EQ(t["name"], "truck");
  // the world's driver keeps within 3 % of the schedule's 15 km/h (truck_driver.hpp)
  EXPECT_NEAR(t["speed_m_s"].get<double>(), 15.0 / 3.6, 0.03 * 15.0 / 3.6 + 0.02);
  EXPECT_NEAR(t["s_m"].get<double>(), 15.0 / 3.6 * 1.0, 0.03 * 15.0 / 3.6);
  EXPECT_NEAR(t["deck_centre_enu_m"][2].get<double>(), 1.5, kHeightTol_m);
  EXPECT_EQ(error_code(c.request({{"op", "balloons"}})), "not_available");

  TestServer balloons("mbzirc2020.xml", paused());
  TestClient b(balloons.port());
  const Json list = b.request({{"op", "balloons"}})["result"]["balloons"];
  ASSERT_EQ(list.size(), 5u);
  EXPECT_EQ(list[0]["popped"], false);
  EXPECT_NEAR(list[0]["position_enu_m"][2].get<double>(), 2.7, kHeightTol_m);
  EXPECT_EQ(error_code(b.request({{"op", "truck"}})), "not_available");
}

TEST(Api, SubscribersGetEventsWithSequenceNumbers) {
  TestServer server("mbzirc2020.xml", paused());
  TestClient c(server.port()), watcher(server.port());
  const Json sub = watcher.request({{"op", "subscribe_events"}});
  ASSERT_TRUE(sub["ok"]) << sub;
  EXPECT_TRUE(sub["result"]["events"].empty());
  c.request({{"op", "step"}, {"steps", 10}});
  ASSERT_TRUE(c.request({{"op", "kill_vehicle"}, {"vehicle", "uav1"}, {"reason", "test"}})["ok"]);
  c.request({{"op", "step"}, {"steps", 1}});
  const Json e0 = watcher.next_event("sim_event");
  const Json e1 = watcher.next_event("sim_event");
  EXPECT_EQ(e0["type"], "vehicle_killed");
  EXPECT_EQ(e0["seq"], 0);
  EXPECT_EQ(e0["vehicle_name"], "uav1");
  EXPECT_NEAR(e0["time"].get<double>(), 10 * kControlDt_s, kTimeTol_s);
  EXPECT_EQ(e1["type"], "crash");
  EXPECT_EQ(e1["seq"], 1);
  // a one-off query from a sequence number
  const Json later = c.request({{"op", "events"}, {"from_seq", 1}})["result"]["events"];
  ASSERT_EQ(later.size(), 1u);
  EXPECT_EQ(later[0]["type"], "crash");
}

TEST(Api, TheEventLogKeepsTheLatestEventsAndSaysWhereItsBacklogStarts) {
  TestServer server("mbzirc2020.xml", paused());
  RawClient c(server.port());  // pipelines its requests
  TestClient watcher(server.port());
  // more events than the log holds: each motor_failure request records one (pipelined, then every reply)
  constexpr size_t kOver = 100;
  constexpr size_t kRecorded = sim::EventLog::kCapacity + kOver;
  std::string burst;
  for (size_t k = 0; k < kRecorded; ++k) {
    burst += Json({{"op", "motor_failure"}, {"vehicle", "uav1"}, {"rotor", 0}, {"failed", k % 2 == 0}}).dump() + "\n";
  }
  c.send_raw(burst);
  for (size_t k = 0; k < kRecorded; ++k) ASSERT_TRUE(c.reply()["ok"]) << k;
  // the backlog from 0 starts at the oldest event still held, and first_seq says which that is
  const Json all = c.request({{"op", "events"}, {"from_seq", 0}})["result"];
  EXPECT_EQ(all["first_seq"], kOver);
  EXPECT_EQ(all["next_seq"], kRecorded);
  ASSERT_EQ(all["events"].size(), sim::EventLog::kCapacity);
  EXPECT_EQ(all["events"][0]["seq"], kOver);
  EXPECT_EQ(all["events"][0]["type"], "motor_failure");
  // a query from a seq still held gets just the events from there
  const Json tail = c.request({{"op", "events"}, {"from_seq", kRecorded - 2}})["result"];
  ASSERT_EQ(tail["events"].size(), 2u);
  EXPECT_EQ(tail["events"][1]["seq"], kRecorded - 1);
  EXPECT_EQ(c.request({{"op", "status"}})["result"]["events"], kRecorded);
  // a subscriber gets the same backlog, then the stream goes on from next_seq
  const Json sub = watcher.request({{"op", "subscribe_events"}})["result"];
  EXPECT_EQ(sub["first_seq"], kOver);
  EXPECT_EQ(sub["events"].size(), sim::EventLog::kCapacity);
  ASSERT_TRUE(c.request({{"op", "kill_vehicle"}, {"vehicle", "uav1"}})["ok"]);
  EXPECT_EQ(watcher.next_event("sim_event")["seq"], kRecorded);
}

class FakeLink : public LinkControl {
 public:
  bool set_link_down(size_t vehicle, bool down) override {
    last_vehicle = static_cast<int>(vehicle);
    last_down = down;
    return true;
  }
  std::atomic<int> last_vehicle{-1};
  std::atomic<bool> last_down{false};
};

TEST(Api, FaultInjection) {
  FakeLink link;
  TestServer server("mbzirc2020.xml", paused(), &link);
  TestClient c(server.port());
  Json r = c.request({{"op", "motor_failure"}, {"vehicle", 0}, {"rotor", 2}});
  ASSERT_TRUE(r["ok"]) << r;
  EXPECT_EQ(c.request({{"op", "vehicles"}})["result"]["vehicles"][0]["failed_motors"], Json::array({2}));
  EXPECT_EQ(error_code(c.request({{"op", "motor_failure"}, {"vehicle", 0}, {"rotor", 4}})), "bad_field");
  EXPECT_EQ(error_code(c.request({{"op", "motor_failure"}, {"vehicle", 0}})), "missing_field");
  EXPECT_TRUE(c.request({{"op", "gps_glitch"}, {"vehicle", 1}, {"offset_enu_m", {5, 0, 0}}})["ok"]);
  EXPECT_EQ(error_code(c.request({{"op", "gps_glitch"}, {"vehicle", 1}, {"offset_enu_m", {5, 0}}})),
            "bad_field");
  EXPECT_TRUE(c.request({{"op", "gps_denied"}, {"vehicle", 1}, {"denied", true}})["ok"]);
  EXPECT_TRUE(c.request({{"op", "link_drop"}, {"vehicle", "uav1"}, {"down", true}})["ok"]);
  EXPECT_EQ(link.last_vehicle, 1);
  EXPECT_TRUE(link.last_down);
  EXPECT_TRUE(c.request({{"op", "kill_vehicle"}, {"vehicle", 1}})["ok"]);
  EXPECT_EQ(c.request({{"op", "vehicles"}})["result"]["vehicles"][1]["crashed"], true);
  const Json events = c.request({{"op", "events"}})["result"]["events"];
  ASSERT_GE(events.size(), 3u);
  EXPECT_EQ(events[0]["type"], "motor_failure");

  // without an endpoint, link drop is not available
  TestServer bare("empty.xml", paused());
  TestClient d(bare.port());
  EXPECT_EQ(error_code(d.request({{"op", "link_drop"}, {"vehicle", 0}})), "not_available");
}

TEST(Api, GimbalPointingAndReservedCameraOps) {
  TestServer server("mbzirc2020.xml", paused());
  TestClient c(server.port());
  const Json r = c.request({{"op", "gimbal"}, {"gimbal", "uav0_gimbal"}, {"mode", "targets"}, {"pitch_deg", -30}});
  ASSERT_TRUE(r["ok"]) << r;
  EXPECT_EQ(r["result"]["mode"], "targets");
  EXPECT_NEAR(r["result"]["pitch_deg"].get<double>(), -30.0, kAngleTol_deg);
  EXPECT_EQ(error_code(c.request({{"op", "gimbal"}, {"gimbal", "nope"}})), "bad_field");
  EXPECT_EQ(error_code(c.request({{"op", "gimbal"}, {"gimbal", "uav0_gimbal"}, {"mode", "up"}})), "bad_field");
  for (const char* op : {"camera_list", "camera_subscribe", "camera_unsubscribe"}) {
    EXPECT_EQ(error_code(c.request({{"op", op}})), "not_available") << op;
  }
}

TEST(Api, BadInputGetsErrorRepliesAndTheConnectionCarriesOn) {
  TestServer server("mbzirc2020.xml", paused());
  RawClient c(server.port());
  c.send_raw("{not json\n");
  EXPECT_EQ(error_code(c.reply()), "bad_json");
  c.send_raw("[1, 2, 3]\n");
  EXPECT_EQ(error_code(c.reply()), "bad_request");
  c.send_raw("{\"id\": 4}\n");
  Json r = c.reply();
  EXPECT_EQ(error_code(r), "missing_field");
  EXPECT_EQ(r["id"], 4);
  EXPECT_EQ(error_code(c.request({{"op", "fly_to_the_moon"}, {"id", "x"}})), "unknown_op");
  EXPECT_EQ(error_code(c.request({{"op", 7}})), "missing_field");
  EXPECT_EQ(error_code(c.request({{"op", "kill_vehicle"}})), "missing_field");
  EXPECT_EQ(error_code(c.request({{"op", "kill_vehicle"}, {"vehicle", 2}})), "unknown_vehicle");
  EXPECT_EQ(error_code(c.request({{"op", "kill_vehicle"}, {"vehicle", "uav9"}})), "unknown_vehicle");
  EXPECT_EQ(error_code(c.request({{"op", "kill_vehicle"}, {"vehicle", -1}})), "unknown_vehicle");
  EXPECT_EQ(error_code(c.request({{"op", "kill_vehicle"}, {"vehicle", {1}}})), "bad_field");
  EXPECT_EQ(error_code(c.request({{"op", "done"}})), "not_joined");
  // an over-long line (2 MiB, sent in pieces) is answered once and skipped to its newline
  const std::string chunk(64 * 1024, 'x');
  c.send_raw("{\"op\": \"status\", \"pad\": \"");
  for (int i = 0; i < 32; ++i) c.send_raw(chunk);
  c.send_raw("\"}\n");
  EXPECT_EQ(error_code(c.reply()), "line_too_long");
  // blank lines are ignored; the connection still works
  c.send_raw("\n\n");
  const Json ok = c.request({{"op", "status"}, {"id", 99}});
  EXPECT_TRUE(ok["ok"]);
  EXPECT_EQ(ok["id"], 99);
  // and so does the server, for a new connection
  TestClient d(server.port());
  EXPECT_TRUE(d.request({{"op", "status"}})["ok"]);
}

}  // namespace
}  // namespace uavsim::server::api
