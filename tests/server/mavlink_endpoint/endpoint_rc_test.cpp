// The pilot's sticks over MAVLink, as a joystick in a ground station sends them: RC_CHANNELS_OVERRIDE
// (channels 1-4 roll, pitch, throttle, yaw in microseconds) and MANUAL_CONTROL move the vehicle in
// ALT_HOLD, LOITER and STABILIZE the way ArduCopter does. Ground truth checks where it went. The quad of
// empty.xml faces east (ENU +x): stick forward is +x, stick right is -y.
#include <gtest/gtest.h>

#include "mavlink_endpoint/test_gcs.hpp"
#include "uavsim/common/angles.hpp"

namespace uavsim::server::mavlink::testing {
namespace {

constexpr double kHoldAltTolM = 0.3;
// drift off the stick's axis while flying forward or sideways
constexpr double kDriftTolM = 1.0;
constexpr double kCrossTrackTolM = 1.5;

class RcTest : public EndpointTest {
 protected:
  // sends the sticks (microseconds; UINT16_MAX: leave as is) every 0.2 s of sim time for duration_s
  void rc_for(TestGcs& g, double duration_s, std::uint16_t roll, std::uint16_t pitch, std::uint16_t throttle,
              std::uint16_t yaw = 1500, std::uint8_t sysid = 255) {
    const double end = sim_->time_s() + duration_s;
    while (sim_->time_s() < end) {
      msg::RcChannelsOverride m;
      m.target_system = 1;
      m.target_component = 1;
      m.chan1_raw = roll;
      m.chan2_raw = pitch;
      m.chan3_raw = throttle;
      m.chan4_raw = yaw;
      m.chan5_raw = UINT16_MAX;
      m.chan6_raw = UINT16_MAX;
      m.chan7_raw = UINT16_MAX;
      m.chan8_raw = UINT16_MAX;
      g.send(m, sysid);
      sync_client(g);
      step_for(0.2);
      g.poll_once(0);
    }
  }
  Eigen::Vector3d truth() const { return sim_->truth(0).position_enu_m; }
  // GPS ready, the mode set, armed
  void arm_in(TestGcs& g, int mode) {
    msg::Heartbeat hb;
    hb.type = 6;
    hb.autopilot = 8;
    g.send(hb);
    wait_gps_ready(g);
    ASSERT_EQ(command(g, MavCmd::DoSetMode, {1, static_cast<float>(mode)}), 0);
    ASSERT_EQ(command(g, MavCmd::ComponentArmDisarm, {1}), 0);
  }
};

TEST_F(RcTest, AltHoldClimbsOnThrottleHoldsAtMidStickAndLeansWithThePitchStick) {
  auto g = connect();
  arm_in(*g, 2);  // ALT_HOLD
  ASSERT_FALSE(HasFatalFailure());
  // throttle up: take-off and climb at up to PILOT_SPEED_UP (2.5 m/s): 4 s well above 3 m
  rc_for(*g, 4.0, 1500, 1500, 1900);
  const double climbed = truth().z();
  EXPECT_GT(climbed, 3.0);
  EXPECT_LT(climbed, 4.0 * 2.5 + 0.5);
  // mid stick: hold the altitude
  rc_for(*g, 1.0, 1500, 1500, 1500);
  const double held = truth().z();
  rc_for(*g, 3.0, 1500, 1500, 1500);
  EXPECT_NEAR(truth().z(), held, kHoldAltTolM);
  // pitch stick forward (channel 2 low): lean nose down, fly forward (east), altitude kept
  const Eigen::Vector3d before = truth();
  rc_for(*g, 3.0, 1500, 1200, 1500);
  EXPECT_GT(truth().x() - before.x(), 3.0);
  EXPECT_NEAR(truth().y(), before.y(), kDriftTolM);
  EXPECT_NEAR(truth().z(), held, kDriftTolM);
}

TEST_F(RcTest, LoiterFliesWhereTheSticksPointAndHoldsWhenCentred) {
  auto g = connect();
  arm_in(*g, 5);  // LOITER
  ASSERT_FALSE(HasFatalFailure());
  rc_for(*g, 3.0, 1500, 1500, 1900);
  ASSERT_GT(truth().z(), 2.0);
  rc_for(*g, 2.0, 1500, 1500, 1500);
  // roll stick right: fly right (south, -y) at up to WPNAV_SPEED
  const Eigen::Vector3d start = truth();
  rc_for(*g, 3.0, 1800, 1500, 1500);
  EXPECT_LT(truth().y() - start.y(), -3.0);
  EXPECT_NEAR(truth().x(), start.x(), kCrossTrackTolM);
  // centred: brake and hold where it stopped
  rc_for(*g, 4.0, 1500, 1500, 1500);
  const Eigen::Vector3d stopped = truth();
  rc_for(*g, 4.0, 1500, 1500, 1500);
  EXPECT_LT((truth() - stopped).norm(), 0.5);
  // yaw stick right: heading turns clockwise, position held
  const double hdg0 = std::atan2((sim_->truth(0).q_enu_body * Eigen::Vector3d::UnitX()).y(),
                                 (sim_->truth(0).q_enu_body * Eigen::Vector3d::UnitX()).x());
  rc_for(*g, 1.0, 1500, 1500, 1500, 1800);
  const double hdg1 = std::atan2((sim_->truth(0).q_enu_body * Eigen::Vector3d::UnitX()).y(),
                                 (sim_->truth(0).q_enu_body * Eigen::Vector3d::UnitX()).x());
  EXPECT_LT(hdg1 - hdg0, -0.2);  // ENU yaw decreases: clockwise seen from above
  EXPECT_LT((truth() - stopped).norm(), 1.0);
}

TEST_F(RcTest, ManualControlFliesStabilizeAndOtherSystemsAreIgnored) {
  auto g = connect();
  arm_in(*g, 0);  // STABILIZE
  ASSERT_FALSE(HasFatalFailure());
  // sticks from a system other than the ground station (SYSID_MYGCS 255) move nothing
  rc_for(*g, 2.0, 1500, 1500, 2000, 1500, 42);
  EXPECT_LT(truth().z(), 0.2);
  // MANUAL_CONTROL: z is throttle (0-1000): above mid takes off and climbs
  auto manual = [&](double duration_s, std::int16_t x, std::int16_t z) {
    const double end = sim_->time_s() + duration_s;
    while (sim_->time_s() < end) {
      msg::ManualControl m;
      m.target = 1;
      m.x = x;
      m.y = 0;
      m.z = z;
      m.r = 0;
      g->send(m);
      sync_client(*g);
      step_for(0.1);
    }
  };
  manual(1.5, 0, 800);
  EXPECT_GT(truth().z(), 1.0);
  // x forward: leans and flies east
  const Eigen::Vector3d before = truth();
  manual(1.5, 400, 620);
  EXPECT_GT(truth().x() - before.x(), 1.0);
}

TEST_F(RcTest, SticksExpireAfterRcOverrideTime) {
  auto g = connect();
  arm_in(*g, 2);  // ALT_HOLD
  ASSERT_FALSE(HasFatalFailure());
  rc_for(*g, 3.0, 1500, 1500, 1900);
  rc_for(*g, 1.0, 1500, 1500, 1500);
  // forward stick, then silence: after RC_OVERRIDE_TIME (3 s) the sticks count as centred and the
  // vehicle levels out
  auto tilt_deg = [&] {
    const double cz = (sim_->truth(0).q_enu_body * Eigen::Vector3d::UnitZ()).z();
    return std::acos(std::clamp(cz, -1.0, 1.0)) * 180.0 / common::kPi;
  };
  rc_for(*g, 0.6, 1500, 1100, 1500);
  EXPECT_GT(tilt_deg(), 10.0);
  step_for(2.0);  // within RC_OVERRIDE_TIME of the last override: still leaning
  EXPECT_GT(tilt_deg(), 10.0);
  step_for(2.0);
  EXPECT_LT(tilt_deg(), 3.0);
  EXPECT_GT(sim_->truth(0).position_enu_m.z(), 1.0);
}

}  // namespace
}  // namespace uavsim::server::mavlink::testing
