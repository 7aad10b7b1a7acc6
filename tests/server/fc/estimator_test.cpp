// The estimator's promises (fc/estimator.hpp): it settles on a still truth to within the sensors'
// noise, tracks a constant velocity without lag (the third-order inertial-nav filter), rejects a
// GPS jump beyond its 10 m gate and resets to GPS after 5 s of rejections, follows a jump inside
// the gate, and calls GPS lost 0.5 s after the last fix. Driven by the seeded sensor models at the
// FC's 500 Hz.
#include "fc/estimator.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>

#include "fc/params.hpp"
#include "fc/sensors.hpp"

namespace uavsim::server::fc {
namespace {

constexpr double kDtS = 0.002;  // the FC's control step (500 Hz)
constexpr uint64_t kSeed = 7;

// default sensor noise (ParamValues): GPS 0.05 m horizontal at 10 Hz, baro 0.05 m, accelerometer
// 0.03 m/s^2 (a tilt of 0.03 / 9.81 = 3 mrad per sample), compass 0.02 rad of heading. The filters
// average many samples, so a settled estimate lies well inside three single-sample deviations:
constexpr double kPosTolM = 3 * 0.05;    // 0.15 m, horizontal (GPS) and vertical (baro)
constexpr double kVelTolM_S = 3 * 0.05;  // 0.15 m/s, the GPS velocity's own noise, three times
constexpr double kTiltTolRad = 3 * 0.03 / kGravityM_S2;  // 9 mrad
constexpr double kYawTolRad = 0.02;                      // one compass sample's deviation

double tilt_error_rad(const Eigen::Quaterniond& est, const Eigen::Quaterniond& truth) {
  // angle between the two body z axes
  const Eigen::Vector3d ze = est * Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d zt = truth * Eigen::Vector3d::UnitZ();
  return std::atan2(ze.cross(zt).norm(), ze.dot(zt));
}

double yaw_of(const Eigen::Quaterniond& q) {
  const Eigen::Vector3d x = q * Eigen::Vector3d::UnitX();
  return std::atan2(x.y(), x.x());
}

// Sensors and estimator stepped together over a truth given as a function of time.
struct Rig {
  ParamValues params;
  Sensors sensors{kSeed};
  Estimator est;
  SensorFrame frame;
  long step = 0;

  double time_s() const { return step * kDtS; }
  // one control step at the present time; the estimate is updated with dt of the step before
  void tick(const TruthState& truth) {
    const double t = time_s();
    sensors.sample(t, truth, params, &frame);
    est.update(t, step == 0 ? 0.0 : kDtS, frame);
    ++step;
  }
  void run_until(double t_end_s, const std::function<TruthState(double)>& truth_at,
                 const std::function<void(double)>& each = nullptr) {
    while (time_s() < t_end_s - 1e-9) {
      const double t = time_s();
      tick(truth_at(t));
      if (each) each(t);
    }
  }
};

TruthState still_truth() {
  TruthState t;
  t.position_enu_m = Eigen::Vector3d(3.0, -4.0, 12.0);
  // sitting on a 6 degree slope, nose 30 degrees left of east
  t.q_enu_body = Eigen::AngleAxisd(0.5236, Eigen::Vector3d::UnitZ()) *
                 Eigen::AngleAxisd(0.1047, Eigen::Vector3d::UnitX());
  t.on_ground = false;
  return t;
}

TEST(Estimator, SettlesOnAStillTruthWithinTheSensorNoise) {
  Rig rig;
  const TruthState truth = still_truth();
  bool converged_early = false;
  // converged() promises kSettleS = 2 s after both initialisations (at t = 0 here, the first GPS
  // fix and compass sample)
  rig.run_until(
      20.0, [&](double) { return truth; },
      [&](double t) {
        if (t < 2.0 - 1e-9) converged_early = converged_early || rig.est.converged(t);
      });
  EXPECT_FALSE(converged_early);
  EXPECT_TRUE(rig.est.converged(rig.time_s()));
  ASSERT_TRUE(rig.est.attitude_ok());
  ASSERT_TRUE(rig.est.position_ok());
  const EstimatedState& s = rig.est.state();
  EXPECT_TRUE(s.gps_ok);
  EXPECT_LT((s.position_enu_m.head<2>() - truth.position_enu_m.head<2>()).norm(), kPosTolM);
  EXPECT_NEAR(s.position_enu_m.z(), truth.position_enu_m.z(), kPosTolM);
  EXPECT_LT(s.velocity_enu_m_s.norm(), kVelTolM_S);
  EXPECT_LT(tilt_error_rad(s.q_enu_body, truth.q_enu_body), kTiltTolRad);
  EXPECT_NEAR(rig.est.yaw_enu_rad(), yaw_of(truth.q_enu_body), kYawTolRad);
  // still: the kinematic acceleration estimate is ~0 (accelerometer noise 0.03 m/s^2 a sample)
  EXPECT_LT(s.accel_enu_m_s2.norm(), 10 * 0.03);
}

TEST(Estimator, InitialisesAttitudeFromGravityAndCompassAtOnce) {
  // the first sample with an accelerometer and a compass reading sets the attitude from that one
  // draw: the tilt error is one accelerometer sample's noise on two axes (3 mrad each), the yaw
  // error one compass sample's (0.02 rad); five deviations bound a single draw
  Rig rig;
  const TruthState truth = still_truth();
  rig.tick(truth);
  ASSERT_TRUE(rig.est.attitude_ok());
  EXPECT_LT(tilt_error_rad(rig.est.state().q_enu_body, truth.q_enu_body), 5 * 0.03 / kGravityM_S2);
  EXPECT_NEAR(rig.est.yaw_enu_rad(), yaw_of(truth.q_enu_body), 5 * kYawTolRad);
}

TEST(Estimator, TracksAConstantVelocityWithoutLag) {
  // 3 m/s north-east at 1 m/s up: a third-order complementary filter follows a ramp with zero
  // steady-state error, so after the settle the estimate is on the truth, not behind it
  Rig rig;
  const Eigen::Vector3d v(2.0, 2.236, 1.0);  // |v_xy| = 3 m/s
  const Eigen::Vector3d p0(0.0, 0.0, 10.0);
  auto truth_at = [&](double t) {
    TruthState s;
    s.position_enu_m = p0 + v * t;
    s.velocity_enu_m_s = v;
    s.on_ground = false;
    return s;
  };
  rig.run_until(20.0, truth_at);
  const EstimatedState& s = rig.est.state();
  const TruthState truth = truth_at(rig.time_s() - kDtS);
  EXPECT_LT((s.position_enu_m - truth.position_enu_m).norm(), kPosTolM * std::sqrt(2.0));
  EXPECT_LT((s.velocity_enu_m_s - v).norm(), kVelTolM_S);
}

TEST(Estimator, RejectsAGpsJumpBeyondItsGateThenResetsToGpsAfterFiveSeconds) {
  // a 20 m jump is beyond the 10 m gate: the fixes are rejected and the estimate dead-reckons on
  // the IMU until 5 s of rejections reset it to GPS. Dead-reckoning drifts by what the filter had
  // left in velocity (~2 cm/s) and accelerometer bias (a few cm/s^2): 0.5 a t^2 + v t = 0.5 * 0.05
  // * 25 + 0.1, a few tens of centimetres, bounded here by 1 m (a twentieth of the jump)
  Rig rig;
  const TruthState truth = still_truth();
  rig.run_until(10.0, [&](double) { return truth; });
  ASSERT_FALSE(rig.est.gps_glitching());
  const Eigen::Vector3d jump(20.0, 0.0, 0.0);
  rig.sensors.set_gps_glitch(jump);
  double reject_from_s = -1.0, reset_at_s = -1.0;
  double worst_while_rejecting_m = 0.0;
  rig.run_until(
      20.0, [&](double) { return truth; },
      [&](double t) {
        const Eigen::Vector2d p = rig.est.state().position_enu_m.head<2>();
        if (rig.est.gps_glitching()) {
          if (reject_from_s < 0.0) reject_from_s = t;
          worst_while_rejecting_m =
              std::max(worst_while_rejecting_m, (p - truth.position_enu_m.head<2>()).norm());
        } else if (reject_from_s >= 0.0 && reset_at_s < 0.0) {
          reset_at_s = t;
          // the reset puts the estimate on the (jumped) fix, i.e. 20 m east of the truth
          EXPECT_LT((p - (truth.position_enu_m + jump).head<2>()).norm(), kPosTolM);
        }
      });
  ASSERT_GE(reject_from_s, 10.0);
  EXPECT_LT(reject_from_s, 10.0 + 0.1 + 1e-9);  // the first fix after the jump (GPS at 10 Hz)
  EXPECT_LT(worst_while_rejecting_m, 1.0);
  ASSERT_GT(reset_at_s, 0.0);
  // kGlitchResetS = 5 s after the first rejected fix, at the first fix from then (0.1 s apart)
  EXPECT_GE(reset_at_s - reject_from_s, 5.0 - 1e-9);
  EXPECT_LE(reset_at_s - reject_from_s, 5.0 + 0.1 + 1e-9);
  // afterwards the fixes agree again and the estimate stays with them
  EXPECT_FALSE(rig.est.gps_glitching());
  EXPECT_LT((rig.est.state().position_enu_m - (truth.position_enu_m + jump)).head<2>().norm(),
            kPosTolM);
}

TEST(Estimator, FollowsAGpsJumpInsideItsGateWithItsTimeConstant) {
  // a 5 m jump is inside the 10 m gate: accepted, and the estimate moves to it. The horizontal
  // filter's time constant is 1.5 s (poles at -1/1.5 s, triple): after 15 s (10 time constants) the
  // remaining error is far below the noise
  Rig rig;
  const TruthState truth = still_truth();
  rig.run_until(10.0, [&](double) { return truth; });
  const Eigen::Vector3d jump(0.0, 5.0, 0.0);
  rig.sensors.set_gps_glitch(jump);
  bool rejected = false;
  rig.run_until(
      25.0, [&](double) { return truth; },
      [&](double) { rejected = rejected || rig.est.gps_glitching(); });
  EXPECT_FALSE(rejected);
  EXPECT_LT((rig.est.state().position_enu_m - (truth.position_enu_m + jump)).head<2>().norm(),
            kPosTolM);
}

TEST(Estimator, GpsIsLostHalfASecondAfterTheLastFix) {
  // a receiver that stops sending: gps_ok holds for kGpsTimeoutS = 0.5 s after the last fix, then
  // drops; a fix without 3D lock is not ok at once
  Estimator est;
  SensorFrame f;
  f.imu.accel_body_m_s2 = Eigen::Vector3d(0.0, 0.0, kGravityM_S2);
  f.gps.fix_3d = true;
  f.gps.satellites = 12;
  f.gps.hdop = 0.7;
  f.mag_new = true;
  f.gps_new = true;
  f.baro_new = true;
  est.update(0.0, 0.0, f);
  EXPECT_TRUE(est.state().gps_ok);
  f.gps_new = false;
  est.update(0.5, 0.5, f);
  EXPECT_TRUE(est.state().gps_ok);
  est.update(0.502, 0.002, f);
  EXPECT_FALSE(est.state().gps_ok);
  // a new fix restores it; a fix without 3D lock does not
  f.gps_new = true;
  est.update(0.6, 0.098, f);
  EXPECT_TRUE(est.state().gps_ok);
  f.gps.fix_3d = false;
  est.update(0.7, 0.1, f);
  EXPECT_FALSE(est.state().gps_ok);
}

TEST(Estimator, ResetForgetsEverything) {
  Rig rig;
  const TruthState truth = still_truth();
  rig.run_until(3.0, [&](double) { return truth; });
  ASSERT_TRUE(rig.est.converged(rig.time_s()));
  rig.est.reset();
  EXPECT_FALSE(rig.est.attitude_ok());
  EXPECT_FALSE(rig.est.position_ok());
  EXPECT_FALSE(rig.est.converged(rig.time_s()));
  EXPECT_EQ(rig.est.state().position_enu_m, Eigen::Vector3d::Zero());
}

}  // namespace
}  // namespace uavsim::server::fc
