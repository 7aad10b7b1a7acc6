// The position controller's promises (fc/position_control.hpp): the sqrt controller's shape, hover
// thrust m g at zero error, a horizontal thrust that points at the target and stops at the lean
// limit (ANGLE_MAX), velocity targets held to the navigation speeds, a vertical acceleration
// between free fall and 2 g, and an acceleration integrator that removes a mass error.
#include "fc/position_control.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "fc/angles.hpp"
#include "fc/params.hpp"
#include "fc/sensors.hpp"

namespace uavsim::server::fc {
namespace {

constexpr double kDtS = 0.002;  // the FC's control step (500 Hz)
constexpr double kMassKg = 1.5;
constexpr double kHoverN = kMassKg * kGravityM_S2;  // 1.5 * 9.80665 = 14.71 N
constexpr double kTol = 1e-9;
// where the two branches of the sqrt controller meet, 1e-9 m apart
constexpr double kBranchTolM_S = 1e-6;
// the horizontal thrust at the tilt limit
constexpr double kTiltThrustTolN = 1e-6;
constexpr double kExactTol = 1e-12;
// the height a 20 % heavier vehicle settles to, and its thrust, relative to its weight
constexpr double kSettledAltTolM = 0.01;
constexpr double kThrustRelTol = 0.01;

EstimatedState at(const Eigen::Vector3d& position_enu_m,
                  const Eigen::Vector3d& velocity_enu_m_s = Eigen::Vector3d::Zero()) {
  EstimatedState s;
  s.position_enu_m = position_enu_m;
  s.velocity_enu_m_s = velocity_enu_m_s;
  return s;
}

PositionSetpoint hold(const Eigen::Vector3d& position_enu_m) {
  PositionSetpoint sp;
  sp.position_enu_m = position_enu_m;
  return sp;
}

TEST(SqrtController, LinearNearZeroThenTheSpeedThatStopsAtConstantDeceleration) {
  // k = 1 /s, a = 2.5 m/s^2: linear up to |e| = a / k^2 = 2.5 m, then sqrt(2 a (|e| - a / (2 k^2)))
  EXPECT_NEAR(sqrt_controller(1.0, 1.0, 2.5, 0.0), 1.0, kTol);
  EXPECT_NEAR(sqrt_controller(-2.0, 1.0, 2.5, 0.0), -2.0, kTol);
  // e = 10 m: sqrt(2 * 2.5 * (10 - 1.25)) = sqrt(43.75) = 6.614 m/s
  EXPECT_NEAR(sqrt_controller(10.0, 1.0, 2.5, 0.0), std::sqrt(43.75), kTol);
  EXPECT_NEAR(sqrt_controller(-10.0, 1.0, 2.5, 0.0), -std::sqrt(43.75), kTol);
  // continuous where the branches meet: at e = 2.5 m both give 2.5 m/s
  EXPECT_NEAR(sqrt_controller(2.5 + 1e-9, 1.0, 2.5, 0.0), 2.5, kBranchTolM_S);
  // no gain: pure sqrt(2 a |e|), the speed that stops exactly in e; no acceleration limit: linear
  EXPECT_NEAR(sqrt_controller(5.0, 0.0, 2.5, 0.0), 5.0, kTol);
  EXPECT_NEAR(sqrt_controller(5.0, 3.0, 0.0, 0.0), 15.0, kTol);
  // never more than closes the error in one step: e / dt = 0.001 / 0.002 = 0.5 m/s, not k e = 3 m/s
  EXPECT_NEAR(sqrt_controller(0.001, 3000.0, 1e9, kDtS), 0.5, kTol);
}

TEST(PositionController, ZeroErrorGivesHoverThrust) {
  ParamTable t(5000.0);
  PositionController pc;
  const Eigen::Vector3d p(4.0, -2.0, 10.0);
  for (int k = 0; k < 100; ++k) {
    const Eigen::Vector3d thrust =
        pc.update(at(p), 0.0, hold(p), t.values(), t.derived(), kMassKg, kDtS, {});
    // T = m g = 14.71 N straight up, every step (nothing to integrate)
    EXPECT_NEAR(thrust.x(), 0.0, kTol);
    EXPECT_NEAR(thrust.y(), 0.0, kTol);
    EXPECT_NEAR(thrust.z(), kHoverN, kTol);
  }
  EXPECT_NEAR(pc.velocity_target().norm(), 0.0, kTol);
}

TEST(PositionController, HorizontalThrustPointsAtTheTargetAndStopsAtTheLeanLimit) {
  for (double angle_max_cdeg : {3000.0, 1500.0}) {
    ParamTable t(5000.0);
    ASSERT_TRUE(t.set("ANGLE_MAX", angle_max_cdeg));
    PositionController pc;
    const Eigen::Vector3d p(0.0, 0.0, 10.0);
    const Eigen::Vector3d target = p + Eigen::Vector3d(30.0, -40.0, 0.0);  // 50 m away
    const Eigen::Vector3d thrust =
        pc.update(at(p), 0.0, hold(target), t.values(), t.derived(), kMassKg, kDtS, {});
    // velocity target sqrt(2 * 2.5 * (50 - 1.25)) = 15.6 m/s, held to 1.2 WPNAV_SPEED = 12 m/s;
    // its P term alone asks 2 * 12 = 24 m/s^2, far above the lean limit g tan(ANGLE_MAX)
    const double tan_max = std::tan(angle_max_cdeg * 0.01 * kDegToRad);
    const Eigen::Vector2d dir = (target - p).head<2>().normalized();
    EXPECT_NEAR(pc.velocity_target().head<2>().norm(), 12.0, kTol);
    EXPECT_NEAR(thrust.head<2>().norm(), kMassKg * kGravityM_S2 * tan_max, kTiltThrustTolN);
    EXPECT_NEAR(thrust.head<2>().normalized().dot(dir), 1.0, kExactTol);
    // level: the vertical part is still the weight, so the tilt is exactly ANGLE_MAX
    EXPECT_NEAR(thrust.z(), kHoverN, kTol);
    EXPECT_NEAR(std::atan2(thrust.head<2>().norm(), thrust.z()), angle_max_cdeg * 0.01 * kDegToRad,
                kTol);
  }
}

TEST(PositionController, SmallErrorGivesAProportionalVelocityTarget) {
  // 1 m east, inside the sqrt controller's linear zone (2.5 m): velocity target PSC_POSXY_P * 1 m
  ParamTable t(5000.0);
  PositionController pc;
  const Eigen::Vector3d p(0.0, 0.0, 10.0);
  const Eigen::Vector3d thrust = pc.update(at(p), 0.0, hold(p + Eigen::Vector3d(1.0, 0.0, 0.0)),
                                           t.values(), t.derived(), kMassKg, kDtS, {});
  EXPECT_NEAR(pc.velocity_target().x(), 1.0, kTol);
  EXPECT_NEAR(pc.velocity_target().y(), 0.0, kTol);
  EXPECT_GT(thrust.x(), 0.0);
  EXPECT_NEAR(thrust.y(), 0.0, kTol);
}

TEST(PositionController, ClimbAndDescentRatesAreTheNavigationLimits) {
  ParamTable t(5000.0);
  const Eigen::Vector3d p(0.0, 0.0, 50.0);
  {
    // 100 m below the target: climb at WPNAV_SPEED_UP = 2.5 m/s, thrust above the weight
    PositionController pc;
    const Eigen::Vector3d thrust = pc.update(at(p), 0.0, hold(p + Eigen::Vector3d(0, 0, 100)),
                                             t.values(), t.derived(), kMassKg, kDtS, {});
    EXPECT_NEAR(pc.velocity_target().z(), 2.5, kTol);
    EXPECT_GT(thrust.z(), kHoverN);
  }
  {
    // 40 m above: descend at WPNAV_SPEED_DN = 1.5 m/s, thrust below the weight
    PositionController pc;
    const Eigen::Vector3d thrust = pc.update(at(p), 0.0, hold(p - Eigen::Vector3d(0, 0, 40)),
                                             t.values(), t.derived(), kMassKg, kDtS, {});
    EXPECT_NEAR(pc.velocity_target().z(), -1.5, kTol);
    EXPECT_LT(thrust.z(), kHoverN);
  }
  {
    // LAND_SPEED_HIGH above WPNAV_SPEED_DN raises the descent limit to it (3 m/s)
    ASSERT_TRUE(t.set("LAND_SPEED_HIGH", 300.0));
    PositionController pc;
    pc.update(at(p), 0.0, hold(p - Eigen::Vector3d(0, 0, 40)), t.values(), t.derived(), kMassKg,
              kDtS, {});
    EXPECT_NEAR(pc.velocity_target().z(), -3.0, kTol);
  }
}

TEST(PositionController, VerticalAccelerationStaysBetweenFreeFallAndTwoG) {
  ParamTable t(5000.0);
  const Eigen::Vector3d p(0.0, 0.0, 50.0);
  {
    // falling at 20 m/s while holding: PSC_VELZ_P * (0 + 20) = 100 m/s^2 asked, 2 g given
    PositionController pc;
    pc.update(at(p, Eigen::Vector3d(0, 0, -20)), 0.0, hold(p), t.values(), t.derived(), kMassKg,
              kDtS, {});
    EXPECT_NEAR(pc.accel_target().z(), 2.0 * kGravityM_S2, kTol);
  }
  {
    // rising at 20 m/s: -100 m/s^2 asked, -0.8 g given; the thrust never turns negative
    PositionController pc;
    for (int k = 0; k < 500; ++k) {
      const Eigen::Vector3d thrust = pc.update(at(p, Eigen::Vector3d(0, 0, 20)), 0.0, hold(p),
                                               t.values(), t.derived(), kMassKg, kDtS, {});
      EXPECT_NEAR(pc.accel_target().z(), -0.8 * kGravityM_S2, kTol);
      EXPECT_GE(thrust.z(), 0.0);
    }
  }
}

TEST(PositionController, AltHoldPassesTheAccelerationFeedForwardUpToTheLeanLimit) {
  // without use_vel_xy the horizontal acceleration is the setpoint's (a pilot's lean), clipped to
  // g tan(30 deg) = 5.662 m/s^2
  ParamTable t(5000.0);
  PositionController pc;
  const Eigen::Vector3d p(0.0, 0.0, 10.0);
  PositionSetpoint sp = hold(p);
  sp.use_pos_xy = false;
  sp.use_vel_xy = false;
  sp.accel_enu_m_s2 = Eigen::Vector3d(0.0, 2.0, 0.0);
  Eigen::Vector3d thrust = pc.update(at(p), 0.0, sp, t.values(), t.derived(), kMassKg, kDtS, {});
  EXPECT_NEAR(thrust.y(), kMassKg * 2.0, kTol);
  EXPECT_NEAR(thrust.x(), 0.0, kTol);
  sp.accel_enu_m_s2 = Eigen::Vector3d(0.0, -20.0, 0.0);
  thrust = pc.update(at(p), 0.0, sp, t.values(), t.derived(), kMassKg, kDtS, {});
  EXPECT_NEAR(thrust.y(), -kMassKg * kGravityM_S2 * std::tan(30.0 * kDegToRad), kTol);
}

TEST(PositionController, AccelerationIntegratorRemovesAMassError) {
  // the controller believes 1.5 kg, the vehicle weighs 1.8 kg (20 % heavier): the feed-forward m g
  // falls 0.2 * 9.81 = 1.96 m/s^2 short, which the acceleration integrator (PSC_ACCZ_IMAX 5 m/s^2)
  // must supply. A vertical point mass, integrated at the control step, settles on the target with
  // a thrust equal to its true weight.
  ParamTable t(5000.0);
  PositionController pc;
  constexpr double kTrueMassKg = 1.8;
  const Eigen::Vector3d target(0.0, 0.0, 10.0);
  Eigen::Vector3d pos = target, vel = Eigen::Vector3d::Zero();
  double accel_z = 0.0;
  Eigen::Vector3d thrust = Eigen::Vector3d::Zero();
  for (int k = 0; k < 15000; ++k) {  // 30 s
    thrust =
        pc.update(at(pos, vel), accel_z, hold(target), t.values(), t.derived(), kMassKg, kDtS, {});
    accel_z = thrust.z() / kTrueMassKg - kGravityM_S2;
    vel.z() += accel_z * kDtS;
    pos.z() += vel.z() * kDtS;
  }
  EXPECT_NEAR(pos.z(), target.z(), kSettledAltTolM);
  EXPECT_NEAR(thrust.z(), kTrueMassKg * kGravityM_S2, kThrustRelTol * kTrueMassKg * kGravityM_S2);
}

TEST(PositionController, ResetClearsTheIntegrators) {
  // after winding up against a mass error, reset() returns to the bare feed-forward m g
  ParamTable t(5000.0);
  PositionController pc;
  const Eigen::Vector3d p(0.0, 0.0, 10.0);
  for (int k = 0; k < 1000; ++k) {
    pc.update(at(p), -1.0, hold(p), t.values(), t.derived(), kMassKg, kDtS, {});
  }
  pc.reset();
  EXPECT_EQ(pc.velocity_target(), Eigen::Vector3d::Zero());
  const Eigen::Vector3d thrust =
      pc.update(at(p), 0.0, hold(p), t.values(), t.derived(), kMassKg, kDtS, {});
  EXPECT_NEAR(thrust.z(), kHoverN, kTol);
}

}  // namespace
}  // namespace uavsim::server::fc
