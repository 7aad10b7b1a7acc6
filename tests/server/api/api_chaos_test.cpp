// Requests that once stopped the world or lost a reply (issue: "nothing stops the world"), and the
// property behind them: every numeric field of every op, fed the numbers a careless or hostile
// client sends (±1e308, overflow to infinity, denormals, 2^63, -0.0), gets a clear reply, and the
// clock still advances afterwards.
#include <gtest/gtest.h>

#include <map>
#include <set>
#include <string>
#include <vector>

#include "api_fixture.hpp"
#include "radio_server.hpp"

namespace uavsim::server::api {
namespace {

using testing::error_code;
using testing::Json;
using testing::paused;
using testing::RawClient;

double time_s(RawClient& c) {
  return c.request({{"op", "status"}})["result"]["time_s"].get<double>();
}

// One control step; the clock advanced by it.
void expect_clock_advances(RawClient& c, const std::string& after) {
  const double before = time_s(c);
  const Json r = c.request({{"op", "step"}, {"steps", 1}});
  ASSERT_TRUE(r.value("ok", false)) << "after " << after << ": " << r;
  EXPECT_GT(time_s(c), before) << "after " << after;
}

TEST(ApiChaos, ATdmaPeriodPastTheSlotArithmeticIsRefusedAndTheClockGoesOn) {
  // period_s / slot_s past 2^64 made the slot count's cast undefined and the slot loop spin for
  // ever at the next radio_send: no reply, no clock, no SIGTERM
  testing::RadioServer server;
  RawClient c(server.port());
  for (const char* period : {"1e308", "1e18", "1e300", "4e3"}) {
    c.send_raw(
        std::string("{\"op\":\"radio_config\",\"tdma\":true,\"slot_s\":0.005,\"period_s\":") +
        period + "}\n");
    const Json r = c.reply();
    EXPECT_EQ(error_code(r), "bad_field") << period << ": " << r;
    EXPECT_NE(r["error"]["message"].get<std::string>().find("period_s"), std::string::npos) << r;
  }
  // nothing was applied
  EXPECT_EQ(c.request({{"op", "radio_config"}})["result"]["tdma"], false);
  const Json sent =
      c.request({{"op", "radio_send"}, {"vehicle", 0}, {"to", "broadcast"}, {"data_b64", "aGk="}});
  EXPECT_TRUE(sent.value("ok", false)) << sent;
  expect_clock_advances(c, "radio_send");
  // the longest usable period still schedules (an hour, slots of 5 ms: 720000 slots)
  const Json longest =
      c.request({{"op", "radio_config"}, {"tdma", true}, {"slot_s", 0.005}, {"period_s", 3600.0}});
  ASSERT_TRUE(longest.value("ok", false)) << longest;
  EXPECT_TRUE(c.request({{"op", "radio_send"}, {"vehicle", 1}, {"to", 0}, {"data_b64", "aGk="}})
                  .value("ok", false));
  expect_clock_advances(c, "radio_send at T = 3600 s");
}

TEST(ApiChaos, RadioConfigRefusesEveryNumberOutsideItsRange) {
  testing::RadioServer server;
  RawClient c(server.port());
  const Json before = c.request({{"op", "radio_config"}})["result"];
  const std::vector<std::string> fields = {
      "range_m",      "path_loss_exponent", "shadowing_sigma_db", "reference_loss_db",
      "tx_power_dbm", "sensitivity_dbm",    "latency_s",          "slot_s",
      "period_s"};
  // negative, denormal, huge, overflowing to infinity: none is a usable value of these fields
  const std::vector<std::string> values = {"-1", "-1e308", "1e308", "1e999", "-1e999", "4.9e-324"};
  for (const std::string& field : fields) {
    for (const std::string& value : values) {
      // denormal and -1 are usable where 0 or a negative number is in range
      if (value == "4.9e-324" &&
          (field == "latency_s" || field == "shadowing_sigma_db" || field == "reference_loss_db" ||
           field == "tx_power_dbm" || field == "sensitivity_dbm")) {
        continue;
      }
      if (value == "-1" && (field == "tx_power_dbm" || field == "sensitivity_dbm")) continue;
      c.send_raw("{\"op\":\"radio_config\",\"tdma\":true,\"" + field + "\":" + value + "}\n");
      const Json r = c.reply();
      const std::string code = error_code(r);
      EXPECT_TRUE(code == "bad_field" || code == "bad_json")
          << field << " = " << value << ": " << r;
    }
  }
  // a usable value of each is still taken
  const Json ok =
      c.request({{"op", "radio_config"}, {"range_m", 250.0}, {"path_loss_exponent", 3.0}});
  ASSERT_TRUE(ok.value("ok", false)) << ok;
  EXPECT_EQ(ok["result"]["range_m"], 250.0);
  Json after = c.request({{"op", "radio_config"},
                          {"range_m", before["range_m"]},
                          {"path_loss_exponent", before["path_loss_exponent"]}})["result"];
  EXPECT_EQ(after, before);
  expect_clock_advances(c, "radio_config");
}

TEST(ApiChaos, AResumeFromAnotherClientAnswersTheStepInProgress) {
  // B's step used to lose its reply when A resumed the clock, and every later step was `busy`
  testing::TestServer server("empty.xml", paused());
  RawClient a(server.port());
  RawClient b(server.port());
  const double start_s = time_s(a);
  // a step that cannot end by itself here (1e9 control steps), then a request behind it on B
  b.send_raw(
      "{\"op\":\"step\",\"id\":\"s\",\"steps\":1000000000}\n{\"op\":\"status\",\"id\":\"after\"}"
      "\n");
  // the step runs: A sees the clock move while still paused
  Json status;
  for (int polls = 0; polls < 100000; ++polls) {
    status = a.request({{"op", "status"}})["result"];
    if (status["time_s"].get<double>() > start_s) break;
  }
  ASSERT_GT(status["time_s"].get<double>(), start_s) << status;
  EXPECT_EQ(error_code(a.request({{"op", "step"}, {"steps", 1}})), "busy");
  ASSERT_TRUE(a.request({{"op", "resume"}}).value("ok", false));
  // B gets its step's reply first (interrupted, saying how far it got), then the later one
  const Json step = b.reply();
  EXPECT_EQ(step["id"], "s") << step;
  EXPECT_EQ(error_code(step), "interrupted") << step;
  const std::string message = step["error"]["message"].get<std::string>();
  EXPECT_NE(message.find("resume"), std::string::npos) << step;
  EXPECT_EQ(message.find('\n'), std::string::npos) << "a message is one line: " << step;
  EXPECT_EQ(b.reply()["id"], "after");
  // and stepping works again, from either client
  ASSERT_TRUE(a.request({{"op", "pause"}}).value("ok", false));
  expect_clock_advances(a, "the interrupted step");
  expect_clock_advances(b, "the interrupted step");
}

TEST(ApiChaos, APauseOrResetFromAnotherClientAlsoEndsTheStep) {
  testing::TestServer server("empty.xml", paused());
  RawClient a(server.port());
  RawClient b(server.port());
  for (const char* op : {"pause", "reset"}) {
    const double start_s = time_s(a);
    b.send_raw("{\"op\":\"step\",\"id\":1,\"steps\":1000000000}\n");
    for (int polls = 0; polls < 100000 && time_s(a) <= start_s; ++polls) {
    }
    ASSERT_TRUE(a.request({{"op", op}}).value("ok", false)) << op;
    const Json step = b.reply();
    EXPECT_EQ(error_code(step), "interrupted") << op << ": " << step;
    EXPECT_NE(step["error"]["message"].get<std::string>().find(op), std::string::npos) << step;
    expect_clock_advances(b, op);
  }
}

TEST(ApiChaos, AStepsRepliesKeepTheOrderOfItsConnectionsRequests) {
  // a short step: the status sent behind it is answered after it
  testing::TestServer server("empty.xml", paused());
  RawClient b(server.port());
  for (int trial = 0; trial < 20; ++trial) {
    b.send_raw(
        "{\"op\":\"step\",\"id\":1,\"steps\":50}\n{\"op\":\"status\",\"id\":2}\n{\"op\":\"nope\","
        "\"id\":3}\n");
    const Json first = b.reply();
    EXPECT_EQ(first["id"], 1) << first;
    EXPECT_TRUE(first.value("ok", false)) << first;
    EXPECT_EQ(b.reply()["id"], 2);
    EXPECT_EQ(b.reply()["id"], 3);
  }
}

// The numbers of the property test, as JSON text (so that overflow to infinity and -0.0 travel as a
// client writes them).
const std::vector<std::string>& hostile_numbers() {
  static const std::vector<std::string> v = {"1e308",
                                             "-1e308",
                                             "1e999",
                                             "-1e999",
                                             "4.9e-324",
                                             "-4.9e-324",
                                             "-0.0",
                                             "9223372036854775808",
                                             "-9223372036854775808",
                                             "18446744073709551616",
                                             "1e-300",
                                             "0.5"};
  return v;
}

// Every op's numeric fields (docs/protocol.md), with the fields that make a request reach them. An
// op missing here fails the test, so a new op joins the property.
struct OpProbe {
  Json base;                         // the op and the fields it needs
  std::vector<std::string> numbers;  // its numeric fields (top level)
};

std::map<std::string, OpProbe> op_probes() {
  const Json v0 = {{"vehicle", 0}};
  auto with = [](Json base, const std::string& op) {
    base["op"] = op;
    return base;
  };
  std::map<std::string, OpProbe> p;
  p["status"] = {with({}, "status"), {}};
  p["pause"] = {with({}, "pause"), {}};
  p["pause_at"] = {with({}, "pause_at"), {"time_s"}};
  p["resume"] = {with({}, "resume"), {}};
  p["step"] = {with({}, "step"), {"steps", "duration_s"}};
  p["set_rate"] = {with({}, "set_rate"), {"rate"}};
  p["reset"] = {with({}, "reset"), {"seed"}};
  p["events"] = {with({}, "events"), {"from_seq"}};
  p["subscribe_events"] = {with({}, "subscribe_events"), {"from_seq"}};
  p["unsubscribe_events"] = {with({}, "unsubscribe_events"), {}};
  p["lockstep_join"] = {with({{"period_s", 0.1}}, "lockstep_join"),
                        {"period_s", "timeout_s", "from_s"}};
  p["lockstep_leave"] = {with({}, "lockstep_leave"), {}};
  // (no hostile number is a power of two in the ring's range: each is refused, and the connection
  // stays on TCP for the next probe)
  p["lockstep_shm"] = {with({{"requests", true}}, "lockstep_shm"),
                       {"ring_bytes", "request_ring_bytes"}};
  p["done"] = {with({{"tick", 0}}, "done"), {"tick", "busy_until"}};
  p["vehicles"] = {with({}, "vehicles"), {}};
  p["truck"] = {with({}, "truck"), {}};
  p["balloons"] = {with({}, "balloons"), {}};
  p["kill_vehicle"] = {with(v0, "kill_vehicle"), {"vehicle"}};
  p["motor_failure"] = {with({{"vehicle", 0}, {"rotor", 0}, {"failed", false}}, "motor_failure"),
                        {"rotor", "vehicle"}};
  p["gps_glitch"] = {with({{"vehicle", 0}, {"offset_enu_m", {0, 0, 0}}}, "gps_glitch"),
                     {"vehicle"}};
  p["gps_denied"] = {with({{"vehicle", 0}, {"denied", false}}, "gps_denied"), {"vehicle"}};
  p["link_drop"] = {with({{"vehicle", 0}, {"down", false}}, "link_drop"), {"vehicle"}};
  p["gimbal"] = {with({{"vehicle", 0}}, "gimbal"), {"pitch_deg", "yaw_deg"}};
  p["wind"] = {with({}, "wind"),
               {"speed_m_s", "from_deg", "turbulence_sd_m_s", "gust_m_s", "gust_duration_s"}};
  p["radio_send"] = {with({{"vehicle", 0}, {"to", 1}, {"data_b64", "aGk="}}, "radio_send"),
                     {"vehicle", "to"}};
  p["radio_subscribe"] = {with({}, "radio_subscribe"), {"vehicle"}};
  p["radio_unsubscribe"] = {with({}, "radio_unsubscribe"), {"vehicle"}};
  p["radio_stats"] = {with({}, "radio_stats"), {"vehicle"}};
  p["radio_config"] = {with({}, "radio_config"),
                       {"range_m", "tx_power_dbm", "sensitivity_dbm", "reference_loss_db",
                        "path_loss_exponent", "shadowing_sigma_db", "loss", "latency_s", "slot_s",
                        "period_s", "max_queue_frames", "mac_header_bytes"}};
  p["gcs_link_open"] = {with(v0, "gcs_link_open"),
                        {"vehicle", "uav_port", "gcs_port", "gcs_target_port"}};
  p["gcs_link_impair"] = {with(v0, "gcs_link_impair"),
                          {"vehicle", "loss", "latency_s", "outage_s"}};
  p["gcs_link_stats"] = {with(v0, "gcs_link_stats"), {"vehicle"}};
  p["camera_list"] = {with({}, "camera_list"), {}};
  p["camera_subscribe"] = {with({{"camera", "uav0/front"}}, "camera_subscribe"),
                           {"fps", "quality"}};
  p["camera_unsubscribe"] = {with({{"camera", "uav0/front"}}, "camera_unsubscribe"), {}};
  p["camera_blackout"] = {with({{"camera", "uav0/front"}}, "camera_blackout"), {"duration_s"}};
  p["auth"] = {with({}, "auth"), {}};
  return p;
}

TEST(ApiChaos, EveryNumericFieldOfEveryOpTakesHostileNumbersAndTheClockGoesOn) {
  testing::RadioServer server;
  RawClient c(server.port());
  const std::map<std::string, OpProbe> probes = op_probes();
  std::set<std::string> unprobed;
  for (const Json& op : c.hello()["ops"]) {
    if (!probes.count(op.get<std::string>())) unprobed.insert(op.get<std::string>());
  }
  EXPECT_TRUE(unprobed.empty()) << "ops without a probe (add their numeric fields): "
                                << Json(unprobed);
  std::set<std::string> listed;
  for (const Json& op : c.hello()["ops"]) listed.insert(op.get<std::string>());
  for (const auto& [op, probe] : probes)
    EXPECT_TRUE(listed.count(op)) << "a probe of an op the server lacks: " << op;
  size_t answered = 0;
  for (const auto& [op, probe] : probes) {
    for (const std::string& field : probe.numbers) {
      for (const std::string& value : hostile_numbers()) {
        Json base = probe.base;
        base.erase(field);
        std::string line = base.dump();
        line.pop_back();  // the closing brace: the number goes in as text
        line += ",\"" + field + "\":" + value + "}\n";
        c.send_raw(line);
        const Json r = c.reply();
        ASSERT_TRUE(r.is_object()) << "no reply to " << line;
        ++answered;
        // a lockstep join or a pause the value made leaves the clock to the next probe
        c.request({{"op", "lockstep_leave"}});
        c.request({{"op", "pause"}});
        c.request({{"op", "set_rate"}, {"rate", 0}});
      }
      expect_clock_advances(c, op + "." + field);
    }
  }
  EXPECT_GT(answered, 500u);
}

}  // namespace
}  // namespace uavsim::server::api
