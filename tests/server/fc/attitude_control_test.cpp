// The attitude controller's promises (fc/attitude_control.hpp): the attitude target from a thrust
// vector (body z along it, tilt at most ANGLE_MAX, heading kept), body-rate targets P * error with
// the right sign per axis, the shortest way round, clipped to ATC_RATE_*_MAX, the yaw-rate
// feed-forward rotated into the body, and torque = J * PID(rate error) + omega x J omega with
// anti-windup.
#include "fc/attitude_control.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "fc/angles.hpp"
#include "fc/params.hpp"

namespace uavsim::server::fc {
namespace {

constexpr double kDtS = 0.002;  // the FC's control step (500 Hz)
constexpr double kTol = 1e-9;

// the test quad's inertia (tests/server/fc/test_airframes.hpp)
Eigen::Matrix3d quad_inertia() { return Eigen::Vector3d(0.029, 0.029, 0.055).asDiagonal(); }

Eigen::Quaterniond ypr(double yaw, double pitch, double roll) {
  return Eigen::Quaterniond(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
                            Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
                            Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()));
}

double tilt_of(const Eigen::Quaterniond& q) {
  const Eigen::Vector3d z = q * Eigen::Vector3d::UnitZ();
  return std::atan2(z.head<2>().norm(), z.z());
}

double heading_of(const Eigen::Quaterniond& q) {
  const Eigen::Vector3d x = q * Eigen::Vector3d::UnitX();
  return std::atan2(x.y(), x.x());
}

// The rate target the controller asks for one step from rest.
Eigen::Vector3d rate_target_for(const Eigen::Quaterniond& target, const Eigen::Quaterniond& est,
                                const ParamTable& t, double yaw_rate_ff = 0.0) {
  AttitudeController ac;
  ac.update(target, yaw_rate_ff, est, Eigen::Vector3d::Zero(), quad_inertia(), t.values(),
            t.derived(), kDtS, {});
  return ac.rate_target();
}

TEST(AttitudeFromThrust, VerticalThrustIsLevelWithTheAskedHeading) {
  for (double yaw : {0.0, 1.0, -2.5, kPi}) {
    const Eigen::Quaterniond q = attitude_from_thrust(Eigen::Vector3d(0, 0, 15.0), yaw, 0.5);
    EXPECT_NEAR(tilt_of(q), 0.0, kTol);
    EXPECT_NEAR(std::remainder(heading_of(q) - yaw, 2 * kPi), 0.0, kTol);
  }
  // thrust pointing down, or none, gives level too (the FC cannot fly upside down)
  EXPECT_NEAR(tilt_of(attitude_from_thrust(Eigen::Vector3d(3, 1, -5.0), 0.3, 0.5)), 0.0, kTol);
  EXPECT_NEAR(tilt_of(attitude_from_thrust(Eigen::Vector3d::Zero(), 0.3, 0.5)), 0.0, kTol);
}

TEST(AttitudeFromThrust, BodyZFollowsTheThrustUpToTheTiltLimit) {
  // 20 degrees toward north-east, under a 30 degree limit: body z along the thrust exactly
  const double tilt = 20.0 * kDegToRad;
  const Eigen::Vector3d dir(std::sin(tilt) / std::sqrt(2.0), std::sin(tilt) / std::sqrt(2.0),
                            std::cos(tilt));
  Eigen::Quaterniond q = attitude_from_thrust(14.7 * dir, 0.0, 30.0 * kDegToRad);
  EXPECT_NEAR((q * Eigen::Vector3d::UnitZ() - dir).norm(), 0.0, kTol);
  // nearly horizontal thrust (80 degrees) toward -y: limited to 30 degrees, same direction
  const Eigen::Vector3d steep(0.0, -std::sin(80 * kDegToRad), std::cos(80 * kDegToRad));
  q = attitude_from_thrust(steep, 0.0, 30.0 * kDegToRad);
  const Eigen::Vector3d z = q * Eigen::Vector3d::UnitZ();
  EXPECT_NEAR(tilt_of(q), 30.0 * kDegToRad, kTol);
  EXPECT_NEAR(z.x(), 0.0, kTol);
  EXPECT_LT(z.y(), 0.0);
  // the heading while tilted: body x is the asked heading x_c = (cos yaw, sin yaw, 0) projected
  // onto the plane normal to body z (y_b = z_b x x_c, x_b = y_b x z_b: Mellinger and Kumar 2011),
  // so body y is normal to x_c and body x leans toward it
  q = attitude_from_thrust(14.7 * dir, 0.7, 30.0 * kDegToRad);
  const Eigen::Vector3d x_c(std::cos(0.7), std::sin(0.7), 0.0);
  const Eigen::Vector3d z_b = q * Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d x_expected = (x_c - x_c.dot(z_b) * z_b).normalized();
  EXPECT_NEAR((z_b - dir).norm(), 0.0, kTol);
  EXPECT_NEAR(((q * Eigen::Vector3d::UnitX()) - x_expected).norm(), 0.0, kTol);
  EXPECT_NEAR((q * Eigen::Vector3d::UnitY()).dot(x_c), 0.0, kTol);
}

TEST(AttitudeController, RateTargetIsAngleGainTimesErrorWithItsSign) {
  ParamTable t(5000.0);  // ATC_ANG_RLL_P = ATC_ANG_PIT_P = 6, ATC_ANG_YAW_P = 3 (rad/s)/rad
  const Eigen::Quaterniond level = Eigen::Quaterniond::Identity();
  // target rolled right by 0.1 rad (about +x, FLU): +6 * 0.1 = 0.6 rad/s roll rate
  Eigen::Vector3d r = rate_target_for(ypr(0, 0, 0.1), level, t);
  EXPECT_NEAR(r.x(), 0.6, kTol);
  EXPECT_NEAR(r.y(), 0.0, kTol);
  EXPECT_NEAR(r.z(), 0.0, kTol);
  // target pitched by -0.05 rad: 6 * -0.05 = -0.3 rad/s
  r = rate_target_for(ypr(0, -0.05, 0), level, t);
  EXPECT_NEAR(r.y(), -0.3, kTol);
  EXPECT_NEAR(r.x(), 0.0, kTol);
  // target yawed 0.2 rad counter-clockwise: 3 * 0.2 = 0.6 rad/s about body z
  r = rate_target_for(ypr(0.2, 0, 0), level, t);
  EXPECT_NEAR(r.z(), 0.6, kTol);
  // the error is in the body frame: a vehicle yawed 90 degrees, asked for the same yaw and a roll
  // of 0.1 rad, rolls at +0.6 rad/s about its own x (world +y), not about world x
  r = rate_target_for(ypr(kPi / 2, 0, 0.1), ypr(kPi / 2, 0, 0), t);
  EXPECT_NEAR(r.x(), 0.6, kTol);
  EXPECT_NEAR(r.y(), 0.0, kTol);
}

TEST(AttitudeController, YawErrorTakesTheShortWayRound) {
  // from -170 to +170 degrees is 20 degrees clockwise, not 340 counter-clockwise:
  // 3 * (-20 deg) = -1.047 rad/s
  ParamTable t(5000.0);
  const Eigen::Vector3d r =
      rate_target_for(ypr(170 * kDegToRad, 0, 0), ypr(-170 * kDegToRad, 0, 0), t);
  EXPECT_NEAR(r.z(), -3.0 * 20.0 * kDegToRad, kTol);
  // and q, -q are the same attitude
  const Eigen::Quaterniond target = ypr(0.3, 0.1, -0.2);
  Eigen::Quaterniond neg = target;
  neg.coeffs() = -neg.coeffs();
  EXPECT_NEAR((rate_target_for(target, Eigen::Quaterniond::Identity(), t) -
               rate_target_for(neg, Eigen::Quaterniond::Identity(), t))
                  .norm(),
              0.0, kTol);
}

TEST(AttitudeController, RateTargetsAreClippedToTheConfiguredMaxima) {
  ParamTable t(5000.0);
  // 1.5 rad roll error: 6 * 1.5 = 9 rad/s, clipped to ATC_RATE_RP_MAX 360 deg/s = 6.283 rad/s;
  // -1 rad of yaw: 3 * -1 = -3 rad/s, clipped to ATC_RATE_Y_MAX 90 deg/s = 1.571 rad/s
  Eigen::Vector3d r = rate_target_for(ypr(0, 0, 1.5), Eigen::Quaterniond::Identity(), t);
  EXPECT_NEAR(r.x(), 2 * kPi, kTol);
  r = rate_target_for(ypr(-1.0, 0, 0), Eigen::Quaterniond::Identity(), t);
  EXPECT_NEAR(r.z(), -kPi / 2, kTol);
  // a lower limit takes effect: ATC_RATE_RP_MAX = 90 deg/s, a pitch error of 1 rad (6 rad/s)
  ASSERT_TRUE(t.set("ATC_RATE_RP_MAX", 90.0));
  r = rate_target_for(ypr(0, 1.0, 0), Eigen::Quaterniond::Identity(), t);
  EXPECT_NEAR(r.y(), kPi / 2, kTol);
}

TEST(AttitudeController, YawRateFeedForwardIsRotatedIntoTheBody) {
  // on target, rolled 0.3 rad, asked to turn at 0.5 rad/s about world z: in the body that is
  // R^T (0, 0, 0.5) = (0, 0.5 sin 0.3, 0.5 cos 0.3)
  ParamTable t(5000.0);
  const Eigen::Quaterniond q = ypr(0.4, 0, 0.3);
  const Eigen::Vector3d r = rate_target_for(q, q, t, 0.5);
  EXPECT_NEAR(r.x(), 0.0, kTol);
  EXPECT_NEAR(r.y(), 0.5 * std::sin(0.3), kTol);
  EXPECT_NEAR(r.z(), 0.5 * std::cos(0.3), kTol);
}

TEST(AttitudeController, TorqueIsInertiaTimesTheRatePidOutput) {
  // first step from rest, a roll-rate error of 0.5 rad/s: alpha = P e + I e dt (no derivative yet)
  // = 20 * 0.5 + 10 * 0.5 * 0.002 = 10.01 rad/s^2, torque = J_xx alpha = 0.029 * 10.01 N m
  ParamTable t(5000.0);
  AttitudeController ac;
  const Eigen::Vector3d tau = ac.update_rate(Eigen::Vector3d(0.5, 0, 0), Eigen::Vector3d::Zero(),
                                             quad_inertia(), t.values(), kDtS, {});
  EXPECT_NEAR(tau.x(), 0.029 * 10.01, kTol);
  EXPECT_NEAR(tau.y(), 0.0, kTol);
  EXPECT_NEAR(tau.z(), 0.0, kTol);
  // yaw: ATC_RAT_YAW_P = 8, I = 2: a -0.25 rad/s error gives 0.055 * (8 + 2 * 0.002) * -0.25
  AttitudeController ay;
  const Eigen::Vector3d tz = ay.update_rate(Eigen::Vector3d(0, 0, -0.25), Eigen::Vector3d::Zero(),
                                            quad_inertia(), t.values(), kDtS, {});
  EXPECT_NEAR(tz.z(), 0.055 * (8.0 + 2.0 * kDtS) * -0.25, kTol);
}

TEST(AttitudeController, HoldingASteadyRateNeedsOnlyTheGyroscopicTorque) {
  // no rate error: torque = omega x J omega (Euler's equations at constant omega). omega = (1, 0,
  // 2): J omega = (0.029, 0, 0.11), omega x J omega = (0, 2 * 0.029 - 1 * 0.11, 0) = (0, -0.052, 0)
  ParamTable t(5000.0);
  AttitudeController ac;
  const Eigen::Vector3d w(1.0, 0.0, 2.0);
  const Eigen::Vector3d tau = ac.update_rate(w, w, quad_inertia(), t.values(), kDtS, {});
  EXPECT_NEAR(tau.x(), 0.0, kTol);
  EXPECT_NEAR(tau.y(), -0.052, kTol);
  EXPECT_NEAR(tau.z(), 0.0, kTol);
}

TEST(AttitudeController, IntegratorStopsGrowingWhileTheMixerSaturatesAndIsCappedAtImax) {
  ParamTable t(5000.0);
  const Eigen::Vector3d target(0.5, 0, 0);
  // saturated for 10 s: the integrator never grows, the torque stays J P e = 0.029 * 10
  AttitudeController sat;
  Eigen::Vector3d tau;
  for (int k = 0; k < 5000; ++k) {
    tau = sat.update_rate(target, Eigen::Vector3d::Zero(), quad_inertia(), t.values(), kDtS,
                          RateLimits{true, false});
  }
  EXPECT_NEAR(tau.x(), 0.029 * 10.0, kTol);
  // free for 10 s: I e t = 10 * 0.5 * 10 = 50 rad/s^2, capped at ATC_RAT_RLL_IMAX = 20
  AttitudeController free;
  for (int k = 0; k < 5000; ++k) {
    tau = free.update_rate(target, Eigen::Vector3d::Zero(), quad_inertia(), t.values(), kDtS, {});
  }
  EXPECT_NEAR(tau.x(), 0.029 * (10.0 + 20.0), kTol);
  // reset_integrators() drops the I term; relax_i() bleeds it with time constant tau:
  // over one tau in 500 steps of dt, the factor is (tau / (tau + dt))^500 ~ exp(-1)
  AttitudeController relaxed = free;
  relaxed.reset_integrators();
  tau = relaxed.update_rate(target, Eigen::Vector3d::Zero(), quad_inertia(), t.values(), kDtS, {});
  EXPECT_NEAR(tau.x(), 0.029 * (10.0 + 10.0 * 0.5 * kDtS), kTol);
  for (int k = 0; k < 500; ++k) free.relax_i(kDtS, 500 * kDtS);
  tau = free.update_rate(target, Eigen::Vector3d::Zero(), quad_inertia(), t.values(), kDtS, {});
  const double bled = 20.0 * std::pow(1.0 / (1.0 + 1.0 / 500.0), 500);  // 20 * 0.368
  EXPECT_NEAR(tau.x(), 0.029 * (10.0 + bled + 10.0 * 0.5 * kDtS), kTol);
}

}  // namespace
}  // namespace uavsim::server::fc
