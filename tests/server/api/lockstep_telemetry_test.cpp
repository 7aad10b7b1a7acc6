// Lockstep and MAVLink telemetry (docs/protocol.md, lockstep contract): when a client receives tick t on
// the API socket, every MAVLink message its vehicle's endpoint produced at the control steps before t is
// already on the MAVLink socket. So a mission that decides at each tick from the latest telemetry sees the
// same telemetry in every run, and a scripted flight flown twice gives the same log.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "api/api_server.hpp"
#include "app/endpoint_hooks.hpp"
#include "api_fixture.hpp"
#include "mavlink/endpoint.hpp"
#include "mavlink_endpoint/test_gcs.hpp"
#include "physics/world.hpp"
#include "sim/runner.hpp"

namespace uavsim::server::api {
namespace {

using common::mavlink::MavCmd;
using mavlink::testing::TestGcs;
namespace msg = common::mavlink::msg;
using testing::Json;
using testing::TestClient;

// the endpoint's hooks as server_app.cpp wires them
using Hooks = app::EndpointHooks;

// a world, its MAVLink endpoints and the API with the endpoint hooks; the clock held until resume
class MavlinkApiServer {
 public:
  explicit MavlinkApiServer(const std::string& world) {
    physics::ComposeOptions o;
    o.models_dir = UAVSIM_MODELS_DIR;
    sim_ = std::make_unique<sim::Simulation>(
        physics::World::load(std::string(UAVSIM_MODELS_DIR) + "/worlds/" + world, o), sim::SimConfig{});
    objects_ = objects::add_world_objects(*sim_);
    mavlink::EndpointConfig ec;
    ec.base_port = 0;
    mavlink_ = std::make_unique<mavlink::MavlinkServer>(*sim_, ec);
    mavlink_->schedule(sim_->schedule());
    hooks_ = std::make_unique<Hooks>(*mavlink_);
    runner_ = std::make_unique<sim::Runner>(*sim_, 0.0);
    ApiConfig config;
    config.port = 0;
    config.start_paused = true;
    api_ = std::make_unique<ApiServer>(*sim_, runner_.get(), objects_, config);
    api_->set_seq_waiter(hooks_.get());
    runner_->add_gate(sim::Phase::kQueuedTasks, "api", api_->gate());
    api_->start();
    loop_ = std::thread([this] { runner_->run_until(std::numeric_limits<double>::infinity()); });
  }
  ~MavlinkApiServer() {
    runner_->stop();
    api_->shutdown();
    loop_.join();
    api_.reset();
    mavlink_.reset();
  }
  uint16_t port() const { return api_->port(); }
  uint16_t mavlink_port(size_t v) const { return mavlink_->port(v); }
  double control_dt_s() const { return sim_->control_dt_s(); }

 private:
  std::unique_ptr<sim::Simulation> sim_;
  objects::ObjectSet objects_;
  std::unique_ptr<mavlink::MavlinkServer> mavlink_;
  std::unique_ptr<Hooks> hooks_;
  std::unique_ptr<sim::Runner> runner_;
  std::unique_ptr<ApiServer> api_;
  std::thread loop_;
};

// the sequence number of the last message g sent (TestGcs numbers its frames from 0)
uint8_t last_seq(const TestGcs& g) { return static_cast<uint8_t>(g.sent_frames() - 1); }

void command(TestGcs& g, MavCmd cmd, std::array<float, 7> p = {}) {
  msg::CommandLong c;
  c.command = mavlink::testing::cmd_id(cmd);
  c.target_system = 1;
  c.target_component = 1;
  c.param1 = p[0], c.param2 = p[1], c.param3 = p[2], c.param4 = p[3];
  c.param5 = p[4], c.param6 = p[5], c.param7 = p[6];
  g.send(c);
}

void set_interval(TestGcs& g, uint32_t msgid, double interval_s) {
  // MAV_CMD_SET_MESSAGE_INTERVAL: msgid, interval in microseconds
  command(g, MavCmd::SetMessageInterval,
          {static_cast<float>(msgid), static_cast<float>(interval_s * 1e6)});
}

// joins lockstep with period_s and resumes the clock; returns the reply of the join
Json join_and_resume(TestClient& api, double period_s) {
  const Json j = api.request({{"op", "lockstep_join"}, {"period_s", period_s}});
  EXPECT_TRUE(j["ok"]) << j;
  EXPECT_TRUE(api.request({{"op", "resume"}})["ok"]);
  return j;
}

TEST(LockstepTelemetry, EveryTickFindsTheTelemetryOfEveryEarlierControlStep) {
  constexpr double kPeriod_s = 0.01;  // 5 control steps at 500 Hz
  constexpr int kTicks = 250;
  MavlinkApiServer server("empty.xml");
  const double dt_ms = server.control_dt_s() * 1000.0;
  TestGcs gcs(server.mavlink_port(0));
  ASSERT_TRUE(gcs.connected());
  TestClient api(server.port());
  join_and_resume(api, kPeriod_s);

  int checked = 0;
  for (int k = 0; k <= kTicks; ++k) {
    const Json tick = api.next_event("tick");
    ASSERT_FALSE(tick.is_null()) << "no tick " << k;
    const double t_s = tick["time"];
    // what is on the MAVLink socket now, without waiting: the flush happened before the tick was sent
    gcs.poll_once(0);
    Json done = {{"op", "done"}, {"tick", tick["tick"]}};
    if (k == 0) {
      // ATTITUDE at every control step from the control step of this tick on
      set_interval(gcs, msg::Attitude::kId, server.control_dt_s());
      done["mavlink_seq"] = {{"0", last_seq(gcs)}};
    } else {
      // the control step before the tick is t - dt: its ATTITUDE is the latest one here
      const auto att = gcs.last<msg::Attitude>();
      ASSERT_TRUE(att.has_value()) << "no ATTITUDE at tick time " << t_s;
      const auto expected_ms = static_cast<uint32_t>(std::llround(t_s * 1000.0 - dt_ms));
      ASSERT_EQ(att->time_boot_ms, expected_ms) << "at the tick at " << t_s << " s";
      ++checked;
    }
    ASSERT_TRUE(api.request(done)["ok"]);
  }
  EXPECT_EQ(checked, kTicks);
  // every ATTITUDE since the stream started arrived, one per control step: (250 ticks x 10 ms) / 2 ms
  EXPECT_EQ(gcs.count<msg::Attitude>(), static_cast<size_t>(std::llround(kTicks * kPeriod_s * 1000.0 / dt_ms)));
}

// one scripted flight decided from telemetry at lockstep ticks: wait for GPS and pre-arm, GUIDED, arm,
// take off to 5 m, go 5 m north (NED x), land; one log line per tick
std::vector<std::string> fly_scripted() {
  constexpr double kPeriod_s = 0.05;
  constexpr int kMaxTicks = 500;  // 25 s of sim time
  constexpr uint32_t kPrearm = 0x10000000, kGps = 32;
  MavlinkApiServer server("empty.xml");
  TestGcs gcs(server.mavlink_port(0));
  EXPECT_TRUE(gcs.connected());
  TestClient api(server.port());
  join_and_resume(api, kPeriod_s);

  std::vector<std::string> log;
  int phase = 0;
  for (int k = 0; k < kMaxTicks && phase < 4; ++k) {
    const Json tick = api.next_event("tick");
    if (tick.is_null()) {
      ADD_FAILURE() << "no tick " << k;
      break;
    }
    gcs.poll_once(0);
    const auto status = gcs.last<msg::SysStatus>();
    const auto global = gcs.last<msg::GlobalPositionInt>();
    const auto local = gcs.last<msg::LocalPositionNed>();
    const uint64_t sent_before = gcs.sent_frames();
    if (k == 0) {
      msg::Heartbeat hb;
      hb.type = 6;  // MAV_TYPE_GCS
      hb.autopilot = 8;
      gcs.send(hb);
      set_interval(gcs, msg::GlobalPositionInt::kId, 0.02);
      set_interval(gcs, msg::LocalPositionNed::kId, 0.02);
      set_interval(gcs, msg::SysStatus::kId, 0.1);
    } else if (k % 20 == 0) {
      msg::Heartbeat hb;
      hb.type = 6;
      hb.autopilot = 8;
      gcs.send(hb);
    }
    if (phase == 0 && status && (status->onboard_control_sensors_health & kPrearm) &&
        (status->onboard_control_sensors_health & kGps)) {
      command(gcs, MavCmd::DoSetMode, {1, 4});  // custom mode GUIDED
      command(gcs, MavCmd::ComponentArmDisarm, {1});
      command(gcs, MavCmd::NavTakeoff, {0, 0, 0, 0, 0, 0, 5});  // to 5 m
      phase = 1;
    } else if (phase == 1 && global && global->relative_alt >= 4500) {
      msg::SetPositionTargetLocalNed sp;
      sp.target_system = 1;
      sp.target_component = 1;
      sp.coordinate_frame = 1;  // MAV_FRAME_LOCAL_NED
      sp.type_mask = 0x0DF8;    // position only
      sp.x = 5, sp.y = 0, sp.z = -5;
      gcs.send(sp);
      phase = 2;
    } else if (phase == 2 && local && local->x >= 4.5f) {
      command(gcs, MavCmd::NavLand);
      phase = 3;
    } else if (phase == 3 && global && global->relative_alt < 200) {
      phase = 4;
    }
    char line[256];
    std::snprintf(line, sizeof(line), "t=%.3f frames=%zu phase=%d global=%u/%d local=%u/%.6f/%.6f", 
                  tick["time"].get<double>(), gcs.frames().size(), phase, global ? global->time_boot_ms : 0,
                  global ? global->relative_alt : 0, local ? local->time_boot_ms : 0, local ? local->x : 0.f,
                  local ? local->z : 0.f);
    log.emplace_back(line);
    Json done = {{"op", "done"}, {"tick", tick["tick"]}};
    if (gcs.sent_frames() > sent_before) done["mavlink_seq"] = {{"0", last_seq(gcs)}};
    const Json r = api.request(done);
    if (!r.value("ok", false)) {
      ADD_FAILURE() << r;
      break;
    }
  }
  EXPECT_EQ(phase, 4) << "the scripted flight did not finish: " << (log.empty() ? "" : log.back());
  return log;
}

TEST(LockstepTelemetry, ScriptedFlightDecidedOnTelemetryRepeatsExactly) {
  const std::vector<std::string> first = fly_scripted();
  const std::vector<std::string> second = fly_scripted();
  ASSERT_GE(first.size(), 200u);
  ASSERT_EQ(first.size(), second.size());
  for (size_t i = 0; i < first.size(); ++i) ASSERT_EQ(first[i], second[i]) << "log line " << i;
}

}  // namespace
}  // namespace uavsim::server::api
