// The endpoint's protocol behaviour over loopback, against docs/mavlink.md (ArduCopter SITL on the
// wire).
#include <cmath>

#include "test_gcs.hpp"

namespace uavsim::server::mavlink::testing {
namespace {

constexpr double kAnswerS = 1.0;  // sim-time bound for a reply to a request
// streamed message counts over a window: one either side of the rate's figure
constexpr double kCountTol = 1.0;
// time_boot_ms of the last message: within one stream period (4 Hz, 2 Hz) of the sim clock
constexpr double kAttitudeAgeTolMs = 260.0;
constexpr double kMountAgeTolMs = 600.0;
constexpr double kLevelTolRad = 0.05;
constexpr double kOriginTolDeg = 1e-4;
constexpr double kMountAngleTolDeg = 1e-3;
constexpr double kQuatTol = 1e-4;  // float fields

TEST_F(EndpointTest, FirstFrameIsAMavlink2HeartbeatOfAnArduCopterQuad) {
  auto g = connect();
  ASSERT_TRUE(step_until(*g, [&] { return !g->frames().empty(); }, kAnswerS));
  EXPECT_EQ(g->first_byte(), 0xFD);  // pymavlink picks v2 from the first byte
  const Frame& f = g->frames().front();
  ASSERT_EQ(f.msgid, msg::Heartbeat::kId);
  EXPECT_EQ(f.sysid, 1);
  EXPECT_EQ(f.compid, 1);
  const auto hb = msg::Heartbeat::decode(f.payload.data());
  EXPECT_EQ(hb.type, 2);       // MAV_TYPE_QUADROTOR: 4 rotors
  EXPECT_EQ(hb.autopilot, 3);  // MAV_AUTOPILOT_ARDUPILOTMEGA
  EXPECT_EQ(hb.base_mode, 81); // CUSTOM_MODE | STABILIZE | MANUAL_INPUT, disarmed
  EXPECT_EQ(hb.system_status, 3);  // STANDBY on the ground
  EXPECT_EQ(hb.mavlink_version, 3);
  EXPECT_EQ(hb.custom_mode, static_cast<std::uint32_t>(sim_->fc(0).mode()));
}

TEST_F(EndpointTest, StreamsDefaultTelemetryInSimTime) {
  auto g = connect();
  step_for(5.0);
  g->poll_once(0);
  ASSERT_TRUE(wait_for([&] {
    g->poll_once(5);
    return g->count<msg::Heartbeat>() >= 5;
  }));
  // 5 s of sim: HEARTBEAT 1 Hz -> 5 (+1 on connect); POSITION 4 Hz -> 20; EXTENDED_STATUS 2 Hz -> 10
  EXPECT_NEAR(static_cast<double>(g->count<msg::Heartbeat>()), 6.0, kCountTol);
  EXPECT_NEAR(static_cast<double>(g->count<msg::GlobalPositionInt>()), 20.0, kCountTol);
  EXPECT_NEAR(static_cast<double>(g->count<msg::SysStatus>()), 10.0, kCountTol);
  EXPECT_GE(g->count<msg::Attitude>(), 19u);
  EXPECT_GE(g->count<msg::VfrHud>(), 19u);
  EXPECT_GE(g->count<msg::GpsRawInt>(), 9u);
  EXPECT_GE(g->count<msg::LocalPositionNed>(), 19u);
  EXPECT_GE(g->count<msg::SystemTime>(), 9u);
  EXPECT_GE(g->count<msg::BatteryStatus>(), 9u);
  // time_boot_ms is sim time: the last ATTITUDE is within one period of the sim clock
  const auto att = g->last<msg::Attitude>();
  ASSERT_TRUE(att);
  EXPECT_NEAR(att->time_boot_ms, sim_->time_s() * 1000.0, kAttitudeAgeTolMs);
  // at rest on the ground of empty.xml: level, near the origin, GPS position near the geodetic origin
  EXPECT_NEAR(att->roll, 0.0, kLevelTolRad);
  const auto gp = g->last<msg::GlobalPositionInt>();
  EXPECT_NEAR(gp->lat / 1e7, server_->config().origin.lat_deg, kOriginTolDeg);
  EXPECT_NEAR(gp->lon / 1e7, server_->config().origin.lon_deg, kOriginTolDeg);
}

TEST_F(EndpointTest, TheIoThreadIsWokenOnlyByControlStepsThatQueuedFrames) {
  auto g = connect();
  step_for(0.5);
  // default streams (1-4 Hz, ATTITUDE and a few more at 10 Hz or less): far fewer steps send a frame than
  // the 400 control steps a second, and no wake-up goes without a frame
  const double control_steps_per_s = 1.0 / (sim_->physics_dt_s() * sim_->control_decimation());
  std::uint64_t w0 = server_->io_wakeups(), f0 = server_->stats(0).frames_sent;
  step_for(5.0);
  const std::uint64_t streaming = server_->io_wakeups() - w0;
  EXPECT_GT(streaming, 0u);
  EXPECT_LE(streaming, server_->stats(0).frames_sent - f0);
  EXPECT_LT(static_cast<double>(streaming), 0.25 * 5.0 * control_steps_per_s);
  // every stream off: only the 1 Hz heartbeat is left to send, and it still arrives
  msg::RequestDataStream r;
  r.target_system = 1;
  r.req_stream_id = 0;
  r.start_stop = 0;
  g->send(r);
  sync_client(*g);
  step_for(0.5);
  ASSERT_TRUE(server_->flush_queued());  // everything so far on the wire, and read
  g->poll_once(50);
  w0 = server_->io_wakeups();
  const std::size_t heartbeats = g->count<msg::Heartbeat>();
  step_for(3.0);
  EXPECT_LE(server_->io_wakeups() - w0, 4u);  // 3 heartbeats (+1 for a boundary)
  EXPECT_TRUE(wait_for([&] {
    g->poll_once(5);
    return g->count<msg::Heartbeat>() >= heartbeats + 3;
  })) << "heartbeats queued without a per-step wake-up never reached the client";
}

TEST_F(EndpointTest, SysStatusReportsPrearmAndGpsHealthOnceReady) {
  auto g = connect();
  const std::uint32_t kPrearm = 0x10000000, kGps = 32;
  ASSERT_TRUE(step_until(*g, [&] {
    const auto s = g->last<msg::SysStatus>();
    return s && (s->onboard_control_sensors_health & kPrearm) && (s->onboard_control_sensors_health & kGps);
  }, 20.0));
  const auto s = g->last<msg::SysStatus>();
  EXPECT_TRUE(s->onboard_control_sensors_present & kPrearm);
  EXPECT_GT(s->voltage_battery, 10000);
  const auto gps = g->last<msg::GpsRawInt>();
  ASSERT_TRUE(gps);
  EXPECT_EQ(gps->fix_type, 3);
}

TEST_F(EndpointTest, UnknownCommandIsUnsupported) {
  auto g = connect();
  EXPECT_EQ(command(*g, kUnsupportedCmd), 3);  // MAV_RESULT_UNSUPPORTED
  const auto ack = g->last<msg::CommandAck>();
  EXPECT_EQ(ack->target_system, 255);
  EXPECT_EQ(ack->target_component, 190);
}

TEST_F(EndpointTest, BroadcastTargetIsAcceptedOtherSystemsAreIgnored) {
  auto g = connect();
  EXPECT_EQ(command(*g, kUnsupportedCmd, {}, 0), 3);  // target 0 = broadcast: handled
  msg::CommandLong c;
  c.command = cmd_id(kUnsupportedCmd);
  c.target_system = 42;
  g->send(c);
  sync_client(*g);
  const std::size_t acks = g->count<msg::CommandAck>();
  step_for(0.5);
  g->poll_once(50);
  EXPECT_EQ(g->count<msg::CommandAck>(), acks);
  EXPECT_EQ(server_->stats(0).wrong_target, 1u);
}

TEST_F(EndpointTest, SetModeMessageIsAckedWithItsMessageId) {
  auto g = connect();
  wait_gps_ready(*g);  // GUIDED needs a position estimate
  msg::SetMode m;
  m.target_system = 1;
  m.base_mode = 1;
  m.custom_mode = 4;  // GUIDED
  g->send(m);
  sync_client(*g);
  ASSERT_TRUE(step_until(*g, [&] { return g->count<msg::CommandAck>() > 0; }, kAnswerS));
  EXPECT_EQ(g->last<msg::CommandAck>()->command, 11);
  EXPECT_EQ(g->last<msg::CommandAck>()->result, 0);
  EXPECT_EQ(sim_->fc(0).mode(), fc::Mode::kGuided);
  ASSERT_TRUE(step_until(*g, [&] { return g->last<msg::Heartbeat>()->custom_mode == 4; }, 2.0));
  // an unknown mode number fails, a mode without CUSTOM_MODE_ENABLED fails
  EXPECT_EQ(command(*g, MavCmd::DoSetMode, {1, 99}), 4);
  EXPECT_EQ(command(*g, MavCmd::DoSetMode, {0, 5}), 4);
}

TEST_F(EndpointTest, ArmDisarmFollowArduCopterRules) {
  auto g = connect();
  wait_gps_ready(*g);
  EXPECT_EQ(command(*g, MavCmd::DoSetMode, {1, 4}), 0);        // GUIDED
  EXPECT_EQ(command(*g, MavCmd::ComponentArmDisarm, {1}), 0);  // arm
  EXPECT_TRUE(sim_->fc(0).armed());
  EXPECT_EQ(command(*g, MavCmd::ComponentArmDisarm, {1}), 0);  // already armed: accepted
  ASSERT_TRUE(step_until(
      *g, [&] { return has_flag(g->last<msg::Heartbeat>()->base_mode, MavModeFlag::SafetyArmed); },
      2.0));
  EXPECT_EQ(command(*g, MavCmd::ComponentArmDisarm, {7}),
            3);  // param1 neither 0 nor 1: unsupported
  EXPECT_EQ(command(*g, MavCmd::ComponentArmDisarm, {0}), 0);  // disarm on the ground
  EXPECT_FALSE(sim_->fc(0).armed());
  EXPECT_EQ(command(*g, MavCmd::NavTakeoff, {0, 0, 0, 0, 0, 0, 10}),
            4);  // take-off while disarmed: FAILED
}

TEST_F(EndpointTest, ParamListStreamsEveryIndexWithCount) {
  auto g = connect();
  msg::ParamRequestList r;
  r.target_system = 1;
  g->send(r);
  sync_client(*g);
  const std::size_t count = sim_->fc(0).param_names().size();
  ASSERT_GT(count, 0u);
  ASSERT_TRUE(step_until(*g, [&] { return g->count<msg::ParamValue>() >= count; }, 2.0));
  std::vector<bool> seen(count, false);
  for (const auto& v : g->all<msg::ParamValue>()) {
    EXPECT_EQ(v.param_count, count);
    // REAL32, or the integer type ArduPilot stores it in (INT8 = 2, INT16 = 4, INT32 = 6)
    EXPECT_TRUE(v.param_type == 9 || v.param_type == 2 || v.param_type == 4 || v.param_type == 6) << v.param_type;
    ASSERT_LT(v.param_index, count);
    seen[v.param_index] = true;
    EXPECT_EQ(std::string(get_string(v.param_id)), sim_->fc(0).param_names()[v.param_index]);
  }
  EXPECT_TRUE(std::all_of(seen.begin(), seen.end(), [](bool b) { return b; }));
  EXPECT_GE(g->count<msg::Statustext>(), 1u);  // the banner comes first
}

TEST_F(EndpointTest, AClientThatConnectsAroundAResetIsStillServed) {
  // the client's connect waits in the endpoint's inbox for a drain task on the loop; a world reset
  // drops queued tasks, and the vehicle's links used to be served never again (no heartbeat)
  auto g = connect();
  sim_->reset(1);
  ASSERT_TRUE(step_until(*g, [&] { return g->count<msg::Heartbeat>() > 0; }, 2.0));
  // and what it sends after the reset is answered
  msg::ParamRequestRead rd;
  rd.target_system = 1;
  rd.param_index = 0;
  g->send(rd);
  sync_client(*g);
  EXPECT_TRUE(step_until(*g, [&] { return g->count<msg::ParamValue>() > 0; }, kAnswerS));
}

TEST_F(EndpointTest, AnIntegerParameterKeepsTheWholePartAndSaysItsType) {
  // SYSID_THISMAV once stored 1.7, and every PARAM_VALUE said REAL32
  auto g = connect();
  msg::ParamSet s;
  s.target_system = 1;
  set_string(s.param_id, "SYSID_THISMAV");
  s.param_value = 1.7f;
  s.param_type = 9;  // the setter's claim does not change how the vehicle stores it
  g->send(s);
  sync_client(*g);
  ASSERT_TRUE(step_until(*g, [&] { return g->count<msg::ParamValue>() > 0; }, kAnswerS));
  const auto echo = g->last<msg::ParamValue>();
  EXPECT_FLOAT_EQ(echo->param_value, 1.0f);
  EXPECT_EQ(echo->param_type, 4);  // MAV_PARAM_TYPE_INT16, as ArduPilot's AP_Int16
  EXPECT_DOUBLE_EQ(*sim_->fc(0).param("SYSID_THISMAV"), 1.0);
  // a float parameter keeps its fraction
  g->clear();
  set_string(s.param_id, "PSC_POSXY_P");
  s.param_value = 1.25f;
  g->send(s);
  sync_client(*g);
  ASSERT_TRUE(step_until(*g, [&] { return g->count<msg::ParamValue>() > 0; }, kAnswerS));
  EXPECT_EQ(g->last<msg::ParamValue>()->param_type, 9);
  EXPECT_DOUBLE_EQ(*sim_->fc(0).param("PSC_POSXY_P"), 1.25);
}

TEST_F(EndpointTest, ParamSetEchoesAndReadsBackByNameAndIndex) {
  auto g = connect();
  const std::string name = "WPNAV_SPEED";
  ASSERT_TRUE(sim_->fc(0).param(name)) << "the FC has no " << name;
  msg::ParamSet s;
  s.target_system = 1;
  set_string(s.param_id, name);
  s.param_value = 750.0f;
  s.param_type = 9;
  g->send(s);
  sync_client(*g);
  ASSERT_TRUE(step_until(*g, [&] { return g->count<msg::ParamValue>() > 0; }, kAnswerS));
  auto echo = g->last<msg::ParamValue>();
  EXPECT_EQ(std::string(get_string(echo->param_id)), name);
  EXPECT_FLOAT_EQ(echo->param_value, 750.0f);
  EXPECT_EQ(echo->param_index, 65535);
  EXPECT_DOUBLE_EQ(*sim_->fc(0).param(name), 750.0);

  // read by name
  g->clear();
  msg::ParamRequestRead rd;
  rd.target_system = 1;
  rd.param_index = -1;
  set_string(rd.param_id, name);
  g->send(rd);
  sync_client(*g);
  ASSERT_TRUE(step_until(*g, [&] { return g->count<msg::ParamValue>() > 0; }, kAnswerS));
  const auto by_name = g->last<msg::ParamValue>();
  EXPECT_FLOAT_EQ(by_name->param_value, 750.0f);
  // read by index
  g->clear();
  rd.param_index = static_cast<std::int16_t>(by_name->param_index);
  set_string(rd.param_id, "");
  g->send(rd);
  sync_client(*g);
  ASSERT_TRUE(step_until(*g, [&] { return g->count<msg::ParamValue>() > 0; }, kAnswerS));
  EXPECT_EQ(std::string(get_string(g->last<msg::ParamValue>()->param_id)), name);

  // unknown names are ignored silently
  g->clear();
  set_string(s.param_id, "NO_SUCH_PARAM");
  g->send(s);
  sync_client(*g);
  step_for(0.2);
  g->poll_once(20);
  EXPECT_EQ(g->count<msg::ParamValue>(), 0u);
}

TEST_F(EndpointTest, Mavlink1ClientIsAnsweredInMavlink1) {
  auto g = connect(0, Version::kV1);
  EXPECT_EQ(command(*g, kUnsupportedCmd), 3);
  const Frame* ack = g->last_frame(msg::CommandAck::kId);
  ASSERT_NE(ack, nullptr);
  EXPECT_EQ(ack->version, Version::kV1);
  // and a v2 client on the same port still gets v2
  auto g2 = connect();
  EXPECT_EQ(command(*g2, kUnsupportedCmd), 3);
  EXPECT_EQ(g2->last_frame(msg::CommandAck::kId)->version, Version::kV2);
}

TEST_F(EndpointTest, SetMessageIntervalChangesARate) {
  auto g = connect();
  // ATTITUDE_QUATERNION is not streamed by default; ask for 10 Hz
  EXPECT_EQ(command(*g, MavCmd::SetMessageInterval, {31, 100000}), 0);
  g->clear();
  step_for(2.0);
  ASSERT_TRUE(wait_for([&] {
    g->poll_once(5);
    return g->count<msg::AttitudeQuaternion>() >= 19;
  }));
  EXPECT_NEAR(static_cast<double>(g->count<msg::AttitudeQuaternion>()), 20.0, kCountTol);
  // -1 stops it; an unknown message id fails
  EXPECT_EQ(command(*g, MavCmd::SetMessageInterval, {31, -1}), 0);
  EXPECT_EQ(command(*g, MavCmd::SetMessageInterval, {9999, 100000}), 4);
  g->clear();
  step_for(1.0);
  g->poll_once(50);
  EXPECT_EQ(g->count<msg::AttitudeQuaternion>(), 0u);
}

TEST_F(EndpointTest, RequestDataStreamSetsAGroupRate) {
  auto g = connect();
  msg::RequestDataStream r;
  r.target_system = 1;
  r.req_stream_id = 6;  // POSITION
  r.req_message_rate = 10;
  r.start_stop = 1;
  g->send(r);
  sync_client(*g);
  step_for(0.01);
  g->poll_once(20);
  g->clear();
  step_for(2.0);
  ASSERT_TRUE(wait_for([&] {
    g->poll_once(5);
    return g->count<msg::GlobalPositionInt>() >= 19;
  }));
  EXPECT_NEAR(static_cast<double>(g->count<msg::GlobalPositionInt>()), 20.0, kCountTol);
  // stop ALL: only heartbeats remain
  r.req_stream_id = 0;
  r.start_stop = 0;
  g->send(r);
  sync_client(*g);
  step_for(0.01);
  g->poll_once(20);
  g->clear();
  step_for(2.0);
  g->poll_once(50);
  EXPECT_EQ(g->count<msg::GlobalPositionInt>(), 0u);
  EXPECT_EQ(g->count<msg::SysStatus>(), 0u);
  EXPECT_GE(g->count<msg::Heartbeat>(), 1u);
}

TEST_F(EndpointTest, RequestMessageAndCapabilities) {
  auto g = connect();
  EXPECT_EQ(command(*g, MavCmd::RequestMessage, {148}), 0);  // AUTOPILOT_VERSION
  ASSERT_TRUE(step_until(*g, [&] { return g->count<msg::AutopilotVersion>() > 0; }, kAnswerS));
  const std::uint64_t caps = g->last<msg::AutopilotVersion>()->capabilities;
  for (std::uint64_t bit : {4u, 8u, 128u, 8192u, 2u}) EXPECT_TRUE(caps & bit) << bit;
  EXPECT_EQ(command(*g, MavCmd::RequestAutopilotCapabilities, {1}), 0);
  ASSERT_TRUE(step_until(*g, [&] { return g->count<msg::AutopilotVersion>() > 1; }, kAnswerS));
  EXPECT_EQ(command(*g, MavCmd::RequestMessage, {245}), 0);  // EXTENDED_SYS_STATE
  ASSERT_TRUE(step_until(*g, [&] { return g->count<msg::ExtendedSysState>() > 0; }, kAnswerS));
  EXPECT_EQ(g->last<msg::ExtendedSysState>()->landed_state, 1);  // ON_GROUND
  EXPECT_EQ(command(*g, MavCmd::RequestMessage, {60000}), 4);    // unknown id: FAILED
}

TEST_F(EndpointTest, TimesyncRequestIsAnsweredWithSimTime) {
  auto g = connect();
  step_for(1.0);
  const double sent_at_s = sim_->time_s();
  msg::Timesync t;
  t.tc1 = 0;
  t.ts1 = 123456789;
  g->send(t);
  sync_client(*g);
  ASSERT_TRUE(step_until(*g, [&] {
    for (const auto& r : g->all<msg::Timesync>()) if (r.ts1 == 123456789 && r.tc1 != 0) return true;
    return false;
  }, kAnswerS));
  for (const auto& r : g->all<msg::Timesync>()) {
    if (r.ts1 != 123456789) continue;
    // handled at the first control step after it arrived: between sending and now, in sim time
    EXPECT_GE(r.tc1 * 1e-9, sent_at_s - 1e-9);
    EXPECT_LE(r.tc1 * 1e-9, sim_->time_s());
  }
}

TEST_F(EndpointTest, GimbalCommandsAreStoredForTheCamera) {
  auto g = connect();
  EXPECT_EQ(command(*g, MavCmd::DoMountControl, {-45, 0, 30, 0, 0, 0, 2}), 0);  // DO_MOUNT_CONTROL
  EXPECT_DOUBLE_EQ(server_->gimbal(0).pitch_deg, -45.0);
  EXPECT_DOUBLE_EQ(server_->gimbal(0).yaw_deg, 30.0);
  EXPECT_EQ(command(*g, MavCmd::DoGimbalManagerPitchyaw, {-90, 10, 0, 0, 16}),
            0);  // GIMBAL_MANAGER_PITCHYAW, yaw lock
  EXPECT_DOUBLE_EQ(server_->gimbal(0).pitch_deg, -90.0);
  EXPECT_TRUE(server_->gimbal(0).yaw_earth_frame);
  EXPECT_GE(server_->gimbal(0).stamp_s, 0.0);
}

TEST_F(EndpointTest, GimbalAttitudeIsStreamedAfterMountControl) {
  auto g = connect();
  EXPECT_EQ(command(*g, MavCmd::DoMountControl, {-90, 0, 0, 0, 0, 0, 2}),
            0);  // DO_MOUNT_CONTROL: straight down
  g->clear();
  ASSERT_TRUE(step_until(*g, [&] {
    return g->count<msg::MountOrientation>() > 0 && g->count<msg::GimbalDeviceAttitudeStatus>() > 0;
  }, 2.0)) << "gimbal attitude is not streamed";
  const auto mo = g->last<msg::MountOrientation>();
  EXPECT_NEAR(mo->pitch, -90.0, kMountAngleTolDeg);
  EXPECT_NEAR(mo->roll, 0.0, kMountAngleTolDeg);
  EXPECT_NEAR(mo->yaw, 0.0, kMountAngleTolDeg);
  EXPECT_NEAR(mo->time_boot_ms, sim_->time_s() * 1000.0, kMountAgeTolMs);
  // the quaternion (w x y z) is a -90 deg pitch about y: w = cos(-45 deg), y = sin(-45 deg)
  const auto gd = g->last<msg::GimbalDeviceAttitudeStatus>();
  EXPECT_NEAR(gd->q[0], std::sqrt(0.5), kQuatTol);
  EXPECT_NEAR(gd->q[1], 0.0, kQuatTol);
  EXPECT_NEAR(gd->q[2], -std::sqrt(0.5), kQuatTol);
  EXPECT_NEAR(gd->q[3], 0.0, kQuatTol);
  EXPECT_TRUE(has_flag(gd->flags, GimbalDeviceFlags::YawInVehicleFrame));
  EXPECT_EQ(gd->gimbal_device_id, 1);
  // a few Hz: EXTRA3 at 2 Hz by default
  g->clear();
  step_for(2.0);
  ASSERT_TRUE(wait_for([&] {
    g->poll_once(5);
    return g->count<msg::MountOrientation>() >= 3;
  }));
  EXPECT_NEAR(static_cast<double>(g->count<msg::GimbalDeviceAttitudeStatus>()), 4.0, kCountTol);
}

TEST_F(EndpointTest, GcsHeartbeatsAreCountedAsHandled) {
  auto g = connect();
  msg::Heartbeat hb;
  hb.type = 6;
  hb.autopilot = 8;
  g->send(hb);
  sync_client(*g);
  step_for(0.01);
  EXPECT_EQ(server_->stats(0).frames_handled, 1u);
  EXPECT_EQ(server_->stats(0).unhandled_messages, 0u);
}

TEST_F(EndpointTest, SeveralClientsEachGetTelemetryAndTheirOwnAcks) {
  auto a = connect();
  auto b = connect();
  EXPECT_EQ(server_->client_count(0), 2u);
  EXPECT_EQ(command(*a, kUnsupportedCmd), 3);
  step_for(1.5);
  a->poll_once(20);
  b->poll_once(20);
  EXPECT_GE(b->count<msg::Heartbeat>(), 1u);
  EXPECT_EQ(b->count<msg::CommandAck>(), 0u);  // the ack went to the asker only
}

class HexaEndpointTest : public EndpointTest {
 protected:
  void SetUp() override { start("hexa.xml"); }
};

TEST_F(HexaEndpointTest, HexaReportsHexarotor) {
  auto g = connect();
  ASSERT_TRUE(step_until(*g, [&] { return g->count<msg::Heartbeat>() > 0; }, kAnswerS));
  EXPECT_EQ(g->last<msg::Heartbeat>()->type, 13);  // MAV_TYPE_HEXAROTOR
}

}  // namespace
}  // namespace uavsim::server::mavlink::testing
