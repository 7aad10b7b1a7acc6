// Numbers out of range at the MAVLink edge: each is refused with an error the sender can see, and the
// values that once hung the loop thread (an angle wrap looping on 1e30) no longer stop the vehicle even
// when they reach the flight controller directly.
#include <cmath>
#include <limits>

#include "test_gcs.hpp"
#include "uavsim/common/angles.hpp"

namespace uavsim::server::mavlink::testing {
namespace {

constexpr int kAccepted = 0, kDenied = 2, kFailed = 4;
constexpr int kMissionError = 1;
constexpr double kHeadingTolRad = 0.15;
constexpr double kAltTolM = 0.5;
constexpr double kYawRateTolRad_S = 0.15;

class RangeTest : public EndpointTest {
 protected:
  // GUIDED, arm, take off to 3 m; returns once telemetry says it is there
  void take_off(TestGcs& g) {
    wait_gps_ready(g);
    ASSERT_EQ(command(g, MavCmd::DoSetMode, {1, 4}), kAccepted);
    ASSERT_EQ(command(g, MavCmd::ComponentArmDisarm, {1}), kAccepted);
    ASSERT_EQ(command(g, MavCmd::NavTakeoff, {0, 0, 0, 0, 0, 0, 3}), kAccepted);
    ASSERT_TRUE(step_until(g, [&] {
      const auto p = g.last<msg::GlobalPositionInt>();
      return p && std::abs(p->relative_alt / 1000.0 - 3.0) < 0.5;
    }, 30.0));
  }

  // the vehicle still obeys: CONDITION_YAW to a heading is accepted and flown (ATTITUDE.yaw is NED)
  void expect_turns_to(TestGcs& g, double heading_deg) {
    ASSERT_EQ(command(g, MavCmd::ConditionYaw, {static_cast<float>(heading_deg), 90, 0, 0}),
              kAccepted);
    const double want = heading_deg * common::kPi / 180.0;
    EXPECT_TRUE(step_until(
        g,
        [&] {
          const auto a = g.last<msg::Attitude>();
          return a && std::abs(std::remainder(a->yaw - want, 2 * common::kPi)) < kHeadingTolRad;
        },
        15.0))
        << "vehicle did not turn to " << heading_deg << " deg after the bad input; truth heading "
        <<
        [&] {
          const Eigen::Vector3d fwd = sim_->truth(0).q_enu_body * Eigen::Vector3d::UnitX();
          return 90.0 - std::atan2(fwd.y(), fwd.x()) * 180.0 / common::kPi;
        }()
        << " deg, last ATTITUDE yaw "
        << (g.last<msg::Attitude>() ? g.last<msg::Attitude>()->yaw * 180.0 / common::kPi : -999.0)
        << " at " << (g.last<msg::Attitude>() ? g.last<msg::Attitude>()->time_boot_ms : 0)
        << " ms, yaw target (ENU) " << sim_->fc(0).yaw_target_enu_rad() * 180.0 / common::kPi
        << " ms, sim " << sim_->time_s() << " s, dropped full "
        << server_->stats(0).frames_dropped_full << ", mode "
        << (g.last<msg::Heartbeat>() ? g.last<msg::Heartbeat>()->custom_mode : 99);
  }

  // sends a GUIDED velocity setpoint of zero with this yaw rate (NED, rad/s) and waits until the
  // endpoint has parsed it
  void send_yaw_rate(TestGcs& g, float yaw_rate) {
    msg::SetPositionTargetLocalNed sp;
    sp.target_system = 1;
    sp.coordinate_frame = 1;
    sp.type_mask = 0x05C7;  // velocity + yaw rate
    sp.yaw_rate = yaw_rate;
    g.send(sp);
    sync_client(g);
  }

  // uploads a two-item mission (home placeholder + item) and returns the MISSION_ACK type
  int upload_one(TestGcs& g, const msg::MissionItemInt& item) {
    return upload_mission(g, 2, [&](int seq) { return seq == 0 ? msg::MissionItemInt{} : item; });
  }
};

TEST_F(RangeTest, HugeAnglesAndRatesReachingTheControllerDoNotHangTheLoop) {
  auto g = connect();
  take_off(*g);
  fc::FlightController& fc = sim_->fc(0);
  // the three inputs that once spun the angle wrap forever, given straight to the controller
  EXPECT_EQ(fc.set_yaw({common::kPi / 2.0 - 1e30 * common::kPi / 180.0, false, 0.0}),
            fc::CommandResult::kAccepted);
  step_for(0.5);
  fc::GuidedTarget t;
  t.velocity_enu_m_s = Eigen::Vector3d::Zero();
  t.yaw_rate_rad_s = 3.4e38;
  EXPECT_EQ(fc.set_guided_target(t), fc::CommandResult::kAccepted);
  step_for(0.2);
  fc::MissionItem yaw_item;
  yaw_item.kind = fc::MissionItem::Kind::kConditionYaw;
  yaw_item.yaw_enu_rad = common::kPi / 2.0 - 1e30 * common::kPi / 180.0;
  yaw_item.position_valid = false;
  fc.set_mission({fc::MissionItem{}, yaw_item});
  ASSERT_EQ(command(*g, MavCmd::MissionStart, {0, 0}), kAccepted);  // AUTO runs the yaw item
  step_for(0.2);
  // back in GUIDED the vehicle is as controllable as before
  std::string events;
  for (const sim::Event& e : sim_->events().recent()) {
    events += std::string(sim::event_type_name(e.type)) + " " + e.detail + "; ";
  }
  ASSERT_TRUE(fc.armed()) << events;
  ASSERT_EQ(command(*g, MavCmd::DoSetMode, {1, 4}), kAccepted);
  expect_turns_to(*g, 90.0);
  EXPECT_TRUE(sim_->truth(0).position_enu_m.allFinite());
}

TEST_F(RangeTest, OutOfRangeYawInputsAreRefusedAtTheEdge) {
  auto g = connect();
  take_off(*g);
  EXPECT_EQ(command(*g, MavCmd::ConditionYaw, {1e30f, 0, 0, 0}), kDenied);  // angle
  EXPECT_EQ(command(*g, MavCmd::ConditionYaw, {90, std::numeric_limits<float>::infinity(), 0, 0}),
            kDenied);  // rate
  EXPECT_EQ(command(*g, MavCmd::ConditionYaw, {90, -5, 0, 0}), kDenied);
  // velocity setpoint with yaw_rate 3.4e38: counted as rejected, never applied
  const auto rejected = server_->stats(0).rejected_inputs;
  send_yaw_rate(*g, 3.4e38f);
  step_for(0.1);
  EXPECT_EQ(server_->stats(0).rejected_inputs, rejected + 1);
  // body rates of 1e30 in SET_ATTITUDE_TARGET too
  msg::SetAttitudeTarget at;
  at.target_system = 1;
  at.type_mask = 128;  // rates only
  at.body_yaw_rate = 1e30f;
  at.thrust = 0.5f;
  g->send(at);
  sync_client(*g);
  step_for(0.1);
  EXPECT_EQ(server_->stats(0).rejected_inputs, rejected + 2);
  expect_turns_to(*g, 180.0);
}

// A yaw rate the edge accepts (under its 35 rad/s gyro bound) but the vehicle cannot fly: it turns
// at ATC_RATE_Y_MAX (90 deg/s) and holds its altitude and level. The heading command once ran away
// from the vehicle at 30 rad/s; near 180 deg of error the attitude target tilted it, and it tumbled
// to the ground within 2 s.
TEST_F(RangeTest, AYawRateAboveTheVehiclesMaximumIsFlownAtItWithoutTumbling) {
  auto g = connect();
  take_off(*g);
  // settled at 3 m (take_off returns when telemetry says it is there, at a sim time that depends on
  // how fast the I/O thread ran)
  step_for(3.0);
  send_yaw_rate(*g, 30.0f);
  const double z0 = sim_->truth(0).position_enu_m.z();
  double max_tilt_rate = 0.0, max_tilt_deg = 0.0, yaw_rate_sum = 0.0;
  int samples = 0;
  const double end = sim_->time_s() + 2.5;
  while (sim_->time_s() < end) {
    step_for(0.01);
    const fc::TruthState tr = sim_->truth(0);
    max_tilt_rate = std::max(max_tilt_rate, tr.rate_body_rad_s.head<2>().norm());
    const double up = (tr.q_enu_body * Eigen::Vector3d::UnitZ()).z();
    max_tilt_deg =
        std::max(max_tilt_deg, std::acos(std::clamp(up, -1.0, 1.0)) * 180.0 / common::kPi);
    if (sim_->time_s() > end - 1.5) {  // the turn, after a second to reach its rate
      yaw_rate_sum += tr.rate_body_rad_s.z();
      ++samples;
    }
  }
  // a turn at the maximum rate tilts it a little; the runaway tilted it 53 deg at 9 rad/s
  EXPECT_LT(max_tilt_deg, 15.0);
  EXPECT_LT(max_tilt_rate, 3.0);
  EXPECT_NEAR(sim_->truth(0).position_enu_m.z(), z0, kAltTolM);
  // clockwise seen from above (NED yaw rate > 0) is a negative ENU body rate, at 90 deg/s
  EXPECT_NEAR(-yaw_rate_sum / samples, 90.0 * common::kPi / 180.0, kYawRateTolRad_S);
}

TEST_F(RangeTest, MissionItemsOutOfRangeGetAMissionError) {
  auto g = connect();
  msg::MissionItemInt yaw;
  yaw.command = cmd_id(MavCmd::ConditionYaw);
  yaw.frame = 3;
  yaw.param1 = 1e30f;
  EXPECT_EQ(upload_one(*g, yaw), kMissionError);
  msg::MissionItemInt wp;
  wp.command = cmd_id(MavCmd::NavWaypoint);
  wp.frame = 3;
  wp.x = 1'000'000'000;  // 100 degrees of latitude
  wp.y = 1;
  wp.z = 10;
  EXPECT_EQ(upload_one(*g, wp), kMissionError);
  wp.x = 1;
  wp.z = 1e30f;
  EXPECT_EQ(upload_one(*g, wp), kMissionError);
  wp.z = 10;
  wp.param1 = -1;  // negative hold time
  EXPECT_EQ(upload_one(*g, wp), kMissionError);
  // the legacy float item with latitude 1e30 (its conversion to 1e-7 degrees would overflow)
  msg::MissionItem legacy;
  legacy.target_system = 1;
  legacy.command = cmd_id(MavCmd::NavWaypoint);
  legacy.frame = 3;
  legacy.current = 2;
  legacy.x = 1e30f;
  const std::size_t acks = g->count<msg::MissionAck>();
  g->send(legacy);
  sync_client(*g);
  ASSERT_TRUE(step_until(*g, [&] { return g->count<msg::MissionAck>() > acks; }, 1.0));
  EXPECT_EQ(g->last<msg::MissionAck>()->type, kMissionError);
  // a good mission still goes in
  yaw.param1 = 90;
  EXPECT_EQ(upload_one(*g, yaw), 0);
  EXPECT_EQ(sim_->fc(0).mission().size(), 2u);
}

TEST_F(RangeTest, FloatToIntegerFieldsOutOfRangeAreDenied) {
  auto g = connect();
  wait_gps_ready(*g);
  ASSERT_EQ(command(*g, MavCmd::DoSetMode, {1, 4}), kAccepted);  // GUIDED
  // custom_mode 2^32 and 1e30 once became 0 (STABILIZE) through an undefined cast
  EXPECT_EQ(command(*g, MavCmd::DoSetMode, {1, 4294967296.0f}), kDenied);
  EXPECT_EQ(command(*g, MavCmd::DoSetMode, {1, 1e30f}), kDenied);
  EXPECT_EQ(command(*g, MavCmd::DoSetMode, {1e30f, 4}), kDenied);
  EXPECT_EQ(command(*g, MavCmd::DoSetMode, {1, 4.5f}), kDenied);
  EXPECT_EQ(sim_->fc(0).mode(), fc::Mode::kGuided);
  EXPECT_EQ(command(*g, MavCmd::MissionStart, {1e30f, 0}), kDenied);
  EXPECT_EQ(command(*g, MavCmd::MissionStart, {0, -1e30f}), kDenied);
  EXPECT_EQ(command(*g, MavCmd::DoSetMissionCurrent, {4294967296.0f}), kDenied);
  EXPECT_EQ(command(*g, MavCmd::DoChangeSpeed, {1e30f, 5}), kDenied);
  EXPECT_EQ(command(*g, MavCmd::DoChangeSpeed, {1, 1e30f}), kDenied);
  EXPECT_EQ(command(*g, MavCmd::RequestMessage, {1e30f}), kDenied);
  EXPECT_EQ(command(*g, MavCmd::RequestMessage, {-1}), kDenied);
  EXPECT_EQ(command(*g, MavCmd::SetMessageInterval, {1e30f, 1000}), kDenied);
  EXPECT_EQ(command(*g, MavCmd::GetMessageInterval, {1e30f}), kDenied);
  EXPECT_EQ(command(*g, MavCmd::DoMountControl, {0, 0, 0, 0, 0, 0, 1e30f}), kDenied);
  EXPECT_EQ(command(*g, MavCmd::DoGimbalManagerPitchyaw, {0, 0, 0, 0, 1e30f}), kDenied);
  EXPECT_EQ(command(*g, MavCmd::NavTakeoff, {0, 0, 0, 0, 0, 0, 1e30f}), kDenied);
  // the same commands in range still work
  EXPECT_EQ(command(*g, MavCmd::RequestMessage, {0}), kAccepted);
  EXPECT_EQ(command(*g, MavCmd::DoChangeSpeed, {1, 5}), kAccepted);
  EXPECT_EQ(command(*g, MavCmd::DoSetMode, {1, 5}), kAccepted);  // LOITER
  EXPECT_EQ(sim_->fc(0).mode(), fc::Mode::kLoiter);
  EXPECT_EQ(command(*g, MavCmd::DoSetMode, {1, 4294967295.0f}),
            kDenied);  // rounds to 2^32 as a float
  EXPECT_EQ(command(*g, MavCmd::DoSetMode, {1, 4000}),
            kFailed);  // a whole number, but no such mode
}

TEST_F(RangeTest, ParamSetOutOfRangeLeavesTheValue) {
  auto g = connect();
  const double before = *sim_->fc(0).param("WPNAV_SPEED");
  for (float v : {1e30f, -1e30f, std::numeric_limits<float>::infinity()}) {
    msg::ParamSet ps;
    ps.target_system = 1;
    set_string(ps.param_id, "WPNAV_SPEED");
    ps.param_value = v;
    g->send(ps);
  }
  sync_client(*g);
  step_for(0.1);
  EXPECT_EQ(*sim_->fc(0).param("WPNAV_SPEED"), before);
  EXPECT_EQ(server_->stats(0).rejected_inputs, 3u);
}

}  // namespace
}  // namespace uavsim::server::mavlink::testing
