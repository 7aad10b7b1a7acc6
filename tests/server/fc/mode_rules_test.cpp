// Mode-change rules, arming checks and command validation, with the vehicle sitting on the ground.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "fc/flight_controller.hpp"
#include "test_airframes.hpp"

namespace uavsim::server::fc {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// a vehicle resting on the ground; the FC updated at 500 Hz
struct Ground {
  Ground() : af(test::make_quad()), fc(af, 3), cmd(af.rotors.size()) {}
  void run_for(double s) {
    const int n = static_cast<int>(s * 500.0 + 0.5);
    for (int k = 0; k < n; ++k) {
      fc.update(t, truth, battery, cmd.data());
      t += 0.002;
    }
  }
  airframe::AirframeParams af;
  FlightController fc;
  TruthState truth;
  airframe::BatteryState battery;
  std::vector<double> cmd;
  double t = 0.0;
};

TEST(ModeRules, ModeNumbersMatchArduCopter) {
  EXPECT_EQ(mode_from_number(4), Mode::kGuided);
  EXPECT_EQ(mode_from_number(17), Mode::kBrake);
  EXPECT_FALSE(mode_from_number(1).has_value());
  EXPECT_STREQ(mode_name(Mode::kRtl), "RTL");
}

TEST(ModeRules, PositionModesRefusedWithoutGpsFix) {
  Ground g;
  g.fc.set_gps_denied(true);
  g.run_for(3.0);  // no fix
  for (Mode m : {Mode::kAuto, Mode::kGuided, Mode::kLoiter, Mode::kRtl, Mode::kBrake}) {
    EXPECT_EQ(g.fc.set_mode(m), CommandResult::kFailed) << mode_name(m);
  }
  EXPECT_EQ(g.fc.set_mode(Mode::kAltHold), CommandResult::kAccepted);
  EXPECT_EQ(g.fc.set_mode(Mode::kLand), CommandResult::kAccepted);
  // with a fix (and the estimator settled), GUIDED is fine; with GPS denied again it is refused
  g.fc.set_gps_denied(false);
  g.run_for(0.5);
  EXPECT_EQ(g.fc.set_mode(Mode::kGuided), CommandResult::kFailed);  // not converged yet
  g.run_for(3.0);
  EXPECT_EQ(g.fc.set_mode(Mode::kGuided), CommandResult::kAccepted);
  g.fc.set_gps_denied(true);
  g.run_for(1.0);
  EXPECT_FALSE(g.fc.estimate().gps_ok);
  EXPECT_EQ(g.fc.set_mode(Mode::kLoiter), CommandResult::kFailed);
}

TEST(ModeRules, ArmingRefusedInAutoRtlLandBrakeEvenForced) {
  Ground g;
  g.run_for(3.0);
  std::vector<MissionItem> m(2);
  m[1].kind = MissionItem::Kind::kTakeoff;
  g.fc.set_mission(m);
  for (Mode mode : {Mode::kAuto, Mode::kRtl, Mode::kLand, Mode::kBrake}) {
    ASSERT_EQ(g.fc.set_mode(mode), CommandResult::kAccepted) << mode_name(mode);
    EXPECT_EQ(g.fc.arm(true), CommandResult::kDenied) << mode_name(mode);
    EXPECT_FALSE(g.fc.armed());
  }
}

TEST(ModeRules, PrearmChecksBlockUnlessForced) {
  Ground g;
  // nothing sampled yet: the estimator has not converged
  EXPECT_FALSE(g.fc.prearm_ok());
  EXPECT_EQ(g.fc.arm(false), CommandResult::kDenied);
  bool saw_prearm = false;
  for (const StatusText& s : g.fc.drain_status_texts()) saw_prearm |= s.text.rfind("PreArm", 0) == 0;
  EXPECT_TRUE(saw_prearm);
  EXPECT_EQ(g.fc.arm(true), CommandResult::kAccepted);
  EXPECT_TRUE(g.fc.armed());
}

TEST(ModeRules, ArmingChecksPassOnceConvergedAndSetHome) {
  Ground g;
  g.truth.position_enu_m = Eigen::Vector3d(3, 4, 0);
  g.run_for(3.0);
  ASSERT_EQ(g.fc.set_mode(Mode::kGuided), CommandResult::kAccepted);
  EXPECT_TRUE(g.fc.prearm_ok());
  EXPECT_EQ(g.fc.arm(false), CommandResult::kAccepted);
  EXPECT_TRUE(g.fc.home_set());
  EXPECT_LT((g.fc.home_enu_m() - g.truth.position_enu_m).norm(), 0.2);
  EXPECT_EQ(g.fc.landed_state(), LandedState::kOnGround);
}

TEST(ModeRules, EmptyBatteryFailsPrearm) {
  Ground g;
  g.battery.consumed_mah = 6000.0;  // more than the 5000 mAh capacity
  g.run_for(3.0);
  EXPECT_FALSE(g.fc.prearm_ok());
}

TEST(ModeRules, TakeoffNeedsArmedGuidedOnGround) {
  Ground g;
  g.run_for(3.0);
  ASSERT_EQ(g.fc.set_mode(Mode::kGuided), CommandResult::kAccepted);
  EXPECT_EQ(g.fc.takeoff(10.0), CommandResult::kDenied);  // disarmed
  ASSERT_EQ(g.fc.arm(false), CommandResult::kAccepted);
  EXPECT_EQ(g.fc.takeoff(kNaN), CommandResult::kInvalid);
  EXPECT_EQ(g.fc.takeoff(10.0), CommandResult::kAccepted);
  EXPECT_EQ(g.fc.landed_state(), LandedState::kTakeoff);
}

TEST(ModeRules, AutoDisarmAfterDisarmDelayOnGround) {
  Ground g;
  g.run_for(3.0);
  ASSERT_EQ(g.fc.set_mode(Mode::kGuided), CommandResult::kAccepted);
  ASSERT_EQ(g.fc.arm(false), CommandResult::kAccepted);
  g.run_for(9.0);
  EXPECT_TRUE(g.fc.armed());
  g.run_for(1.5);  // DISARM_DELAY = 10 s
  EXPECT_FALSE(g.fc.armed());
}

TEST(ModeRules, GcsLossOnGroundDisarms) {
  Ground g;
  ASSERT_EQ(g.fc.set_param("FS_GCS_ENABLE", 1), CommandResult::kAccepted);
  g.fc.on_gcs_heartbeat(0.0);
  g.run_for(3.0);
  ASSERT_EQ(g.fc.set_mode(Mode::kGuided), CommandResult::kAccepted);
  g.fc.on_gcs_heartbeat(g.t);
  ASSERT_EQ(g.fc.arm(false), CommandResult::kAccepted);
  g.run_for(5.5);  // FS_GCS_TIMEOUT = 5 s
  EXPECT_FALSE(g.fc.armed());
}

TEST(ModeRules, CommandsWithNonFiniteValuesAreInvalid) {
  Ground g;
  g.run_for(3.0);
  ASSERT_EQ(g.fc.set_mode(Mode::kGuided), CommandResult::kAccepted);
  GuidedTarget t;
  t.position_enu_m = Eigen::Vector3d(kNaN, 0, 0);
  EXPECT_EQ(g.fc.set_guided_target(t), CommandResult::kInvalid);
  t.position_enu_m.reset();
  t.velocity_enu_m_s = Eigen::Vector3d(2000, 0, 0);  // beyond ArduCopter's 1000 m/s sanity limit
  EXPECT_EQ(g.fc.set_guided_target(t), CommandResult::kInvalid);
  AttitudeTarget a;
  a.q_enu_body = Eigen::Quaterniond(kNaN, 0, 0, 0);
  EXPECT_EQ(g.fc.set_attitude_target(a), CommandResult::kInvalid);
  EXPECT_EQ(g.fc.set_yaw({kNaN, false, 0.0}), CommandResult::kInvalid);
  EXPECT_EQ(g.fc.change_speed(fc::SpeedLimit::kHorizontal, kNaN), CommandResult::kInvalid);
}

TEST(ModeRules, GuidedTargetRefusedOutsideGuided) {
  Ground g;
  g.run_for(3.0);
  ASSERT_EQ(g.fc.set_mode(Mode::kLoiter), CommandResult::kAccepted);
  GuidedTarget t;
  t.position_enu_m = Eigen::Vector3d(1, 0, 5);
  EXPECT_EQ(g.fc.set_guided_target(t), CommandResult::kDenied);
}

TEST(ModeRules, NonFiniteTruthNeverThrowsAndIsCounted) {
  Ground g;
  g.run_for(1.0);
  g.truth.position_enu_m.x() = kNaN;
  EXPECT_NO_THROW(g.run_for(0.1));
  EXPECT_EQ(g.fc.nonfinite_input_count(), 50u);
  for (double c : g.cmd) EXPECT_EQ(c, 0.0);
}

TEST(ModeRules, ArmAndModeEventsProduceStatusTexts) {
  Ground g;
  g.run_for(3.0);
  g.fc.drain_status_texts();
  ASSERT_EQ(g.fc.set_mode(Mode::kGuided), CommandResult::kAccepted);
  ASSERT_EQ(g.fc.arm(false), CommandResult::kAccepted);
  const std::vector<StatusText> texts = g.fc.drain_status_texts();
  ASSERT_EQ(texts.size(), 2u);
  EXPECT_EQ(texts[0].text, "Mode GUIDED");
  EXPECT_EQ(texts[1].text, "Arming motors");
  EXPECT_EQ(texts[1].severity, 6);
}

}  // namespace
}  // namespace uavsim::server::fc
