// The motor monitor's promises (fc/motor_monitor.hpp): on a vehicle of six or more rotors, a rotor
// that stops is named from the gyro and accelerometer alone, after the residual has pointed at it
// for kConfirmS = 0.12 s; a healthy vehicle (noisy sensors, a commanded roll) is never accused;
// nothing is judged on the ground, nor on a quad; a detection holds until reset(). The plant is the
// airframe library's motors and rigid body (rigid_body_plant.hpp), flying open loop at the hover
// command.
#include "fc/motor_monitor.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "fc/gaussian.hpp"
#include "fc/sensors.hpp"
#include "rigid_body_plant.hpp"
#include "test_airframes.hpp"

namespace uavsim::server::fc {
namespace {

constexpr double kDtS = 0.002;      // the FC's control step (500 Hz)
constexpr double kConfirmS = 0.12;  // motor_monitor.cpp: the same candidate for this long
constexpr double kSpinUpS = 0.5;    // on the ground first: 12 motor time constants (0.04 s)
// the hexa hovers with every rotor at half its maximum thrust: speed^2 = 0.5, command sqrt(0.5)
const double kHoverCmd = std::sqrt(0.5);

// A hexa hanging at 50 m at the hover command, its sensors optionally noisy, the monitor fed as the
// FC feeds it: the commands of the step just ended, then the IMU after it.
struct Rig {
  explicit Rig(const airframe::AirframeParams& a, double gyro_sd = 0.0, double accel_sd = 0.0)
      : plant(a),
        monitor(a),
        cmd(a.rotors.size(), kHoverCmd),
        noise(3),
        gyro_sd_(gyro_sd),
        accel_sd_(accel_sd) {
    plant.mutable_truth().position_enu_m = Eigen::Vector3d(0.0, 0.0, 50.0);
    plant.mutable_truth().on_ground = false;
    for (double& s : plant.motors().speed) s = kHoverCmd;
  }
  void step(bool airborne) {
    plant.step(cmd.data(), kDtS);
    const TruthState& t = plant.truth();
    Eigen::Vector3d gyro = t.rate_body_rad_s;
    Eigen::Vector3d f =
        t.q_enu_body.conjugate() * (t.accel_enu_m_s2 + Eigen::Vector3d(0.0, 0.0, kGravityM_S2));
    for (int i = 0; i < 3; ++i) {
      gyro[i] += gyro_sd_ * noise();
      f[i] += accel_sd_ * noise();
    }
    monitor.update(cmd.data(), gyro, f, kDtS, airborne);
    time_s += kDtS;
  }
  // steps until the monitor names a rotor or t_end passes; the time it took, or -1
  double run_until_detection(double duration_s, bool airborne = true) {
    const double t0 = time_s;
    while (time_s < t0 + duration_s - 1e-9) {
      step(airborne);
      if (monitor.lost_rotor() >= 0) return time_s - t0;
    }
    return -1.0;
  }

  test::RigidBodyPlant plant;
  MotorMonitor monitor;
  std::vector<double> cmd;
  Gaussian noise;
  double time_s = 0.0;

 private:
  double gyro_sd_, accel_sd_;
};

TEST(MotorMonitor, NamesTheStoppedRotorOfAHexa) {
  // each rotor in turn stops in flight: its 11.1 N on a 0.45 m arm leave 5 N m of roll/pitch torque
  // (14 rad/s^2 on J = 0.35 kg m^2) and 11.1 N of thrust missing. The rotor spins down with its
  // 0.04 s lag, the residual filter follows in ~0.03 s, then the candidate must hold for 0.12 s:
  // named after at least 0.12 s and, with those lags, well within 0.3 s
  for (int k = 0; k < 6; ++k) {
    Rig rig(test::make_hexa());
    rig.run_until_detection(kSpinUpS, /*airborne=*/false);
    ASSERT_LT(rig.run_until_detection(1.0), 0.0) << "healthy before the failure, rotor " << k;
    rig.plant.motors().failed[k] = true;
    const double t = rig.run_until_detection(1.0);
    EXPECT_EQ(rig.monitor.lost_rotor(), k);
    EXPECT_GE(t, kConfirmS) << "rotor " << k;
    EXPECT_LE(t, 0.3) << "rotor " << k;
  }
}

TEST(MotorMonitor, NoisySensorsOnAHealthyHexaAccuseNoRotor) {
  // the FC's default sensor noise (SIM_GYRO_SD 0.003 rad/s, SIM_ACCEL_SD 0.03 m/s^2) for 20 s: the
  // differentiated gyro noise is ~2 rad/s^2 a sample, far under a lost rotor's 14 rad/s^2 once
  // filtered
  Rig rig(test::make_hexa(), 0.003, 0.03);
  rig.run_until_detection(kSpinUpS, false);
  EXPECT_LT(rig.run_until_detection(20.0), 0.0);
  EXPECT_EQ(rig.monitor.lost_rotor(), -1);
  // the same noise still lets a real loss through
  rig.plant.motors().failed[2] = true;
  EXPECT_GT(rig.run_until_detection(1.0), 0.0);
  EXPECT_EQ(rig.monitor.lost_rotor(), 2);
}

TEST(MotorMonitor, ACommandedRollIsNotALostRotor) {
  // rotors on the left (+y) side up 10 %, the right side down 10 %, for 0.3 s: a large roll torque,
  // but the one the commands explain, so the residual stays small
  const airframe::AirframeParams a = test::make_hexa();
  Rig rig(a);
  rig.run_until_detection(kSpinUpS, false);
  for (std::size_t k = 0; k < a.rotors.size(); ++k) {
    rig.cmd[k] = kHoverCmd * (a.rotors[k].position_body_m.y() > 0.0 ? 1.1 : 0.9);
  }
  EXPECT_LT(rig.run_until_detection(0.3), 0.0);
  EXPECT_GT(rig.plant.truth().rate_body_rad_s.norm(), 1.0);  // it did roll hard
  for (double& c : rig.cmd) c = kHoverCmd;
  EXPECT_LT(rig.run_until_detection(0.3), 0.0);
}

TEST(MotorMonitor, NothingIsJudgedOnTheGround) {
  // not airborne (contact and spin-up transients are not the model's): a stopped rotor is not named
  Rig rig(test::make_hexa());
  rig.run_until_detection(kSpinUpS, false);
  rig.plant.motors().failed[4] = true;
  EXPECT_LT(rig.run_until_detection(1.0, /*airborne=*/false), 0.0);
}

TEST(MotorMonitor, AQuadIsNeverJudged) {
  // kMinRotors = 6: a quad cannot fly on three rotors, so there is nothing to switch to. Its hover
  // command is sqrt(0.5) too (max thrust 2 m g / 4)
  Rig rig(test::make_quad());
  rig.run_until_detection(kSpinUpS, false);
  rig.plant.motors().failed[0] = true;
  EXPECT_LT(rig.run_until_detection(1.0), 0.0);
  EXPECT_EQ(rig.monitor.lost_rotor(), -1);
}

TEST(MotorMonitor, ADetectionHoldsUntilReset) {
  Rig rig(test::make_hexa());
  rig.run_until_detection(kSpinUpS, false);
  rig.plant.motors().failed[1] = true;
  ASSERT_GT(rig.run_until_detection(1.0), 0.0);
  // the rotor comes back (the plant repaired): the detection is latched all the same
  rig.plant.motors().failed[1] = false;
  for (int k = 0; k < 500; ++k) rig.step(true);
  EXPECT_EQ(rig.monitor.lost_rotor(), 1);
  rig.monitor.reset();
  EXPECT_EQ(rig.monitor.lost_rotor(), -1);
}

}  // namespace
}  // namespace uavsim::server::fc
