#include "fc/mixer.hpp"

#include <gtest/gtest.h>

#include <vector>

#include "test_airframes.hpp"

namespace uavsim::server::fc {
namespace {

constexpr double kTolN = 1e-9;
constexpr double kWrenchTol = 1e-9;  // N for the thrust, N m for the torques
constexpr double kCmdTol = 1e-9;
constexpr double kScaleTol = 1e-9;

// the wrench the per-rotor thrusts produce, through the allocation matrix
Eigen::Vector4d wrench_of(const Mixer& m, const std::vector<double>& thrust) {
  Eigen::VectorXd t(static_cast<Eigen::Index>(thrust.size()));
  for (std::size_t k = 0; k < thrust.size(); ++k) t[static_cast<Eigen::Index>(k)] = thrust[k];
  return m.allocation() * t;
}

void hover_is_equal_thrust(const airframe::AirframeParams& af) {
  Mixer m(af);
  const std::size_t n = af.rotors.size();
  std::vector<double> thrust(n), cmd(n);
  // hover: T = m g, shared equally: T_k = m g / n
  const double weight = af.mass_kg * test::kTestGravity;
  const MixerStatus st = m.mix(Eigen::Vector3d::Zero(), weight, thrust.data(), cmd.data());
  for (std::size_t k = 0; k < n; ++k) {
    EXPECT_NEAR(thrust[k], weight / n, kTolN);
    // max thrust is 2 m g / n, so cmd = sqrt(1/2)
    EXPECT_NEAR(cmd[k], std::sqrt(0.5), kCmdTol);
  }
  EXPECT_NEAR(st.thrust_n, weight, kTolN);
  EXPECT_DOUBLE_EQ(st.roll_pitch_scale, 1.0);
}

TEST(Mixer, HoverGivesEqualThrustOnSymmetricQuad) { hover_is_equal_thrust(test::make_quad()); }
TEST(Mixer, HoverGivesEqualThrustOnSymmetricHexa) { hover_is_equal_thrust(test::make_hexa()); }

void pure_torques_are_recovered(const airframe::AirframeParams& af) {
  Mixer m(af);
  const std::size_t n = af.rotors.size();
  std::vector<double> thrust(n), cmd(n);
  const double weight = af.mass_kg * test::kTestGravity;
  // small torques about each axis alone, at hover thrust: A * thrust gives them back exactly
  const Eigen::Vector3d torques[] = {{0.3, 0, 0}, {0, -0.3, 0}, {0, 0, 0.1}, {0.2, 0.1, -0.05}};
  for (const Eigen::Vector3d& tau : torques) {
    const MixerStatus st = m.mix(tau, weight, thrust.data(), cmd.data());
    ASSERT_DOUBLE_EQ(st.roll_pitch_scale, 1.0);
    ASSERT_DOUBLE_EQ(st.yaw_scale, 1.0);
    const Eigen::Vector4d w = wrench_of(m, thrust);
    EXPECT_NEAR(w[0], tau.x(), kWrenchTol);
    EXPECT_NEAR(w[1], tau.y(), kWrenchTol);
    EXPECT_NEAR(w[2], tau.z(), kWrenchTol);
    EXPECT_NEAR(w[3], weight, kWrenchTol);
  }
}

TEST(Mixer, PureTorquesAreRecoveredThroughAllocationQuad) {
  pure_torques_are_recovered(test::make_quad());
}
TEST(Mixer, PureTorquesAreRecoveredThroughAllocationHexa) {
  pure_torques_are_recovered(test::make_hexa());
}

TEST(Mixer, PositiveRollTorqueRaisesLeftRotors) {
  // FLU body: +x roll torque = right side down... r x F: rotors at +y (left) push +x torque
  const airframe::AirframeParams af = test::make_quad();
  Mixer m(af);
  std::vector<double> thrust(4), cmd(4);
  m.mix(Eigen::Vector3d(0.2, 0, 0), 10.0, thrust.data(), cmd.data());
  for (int k = 0; k < 4; ++k) {
    if (af.rotors[k].position_body_m.y() > 0)
      EXPECT_GT(thrust[k], 2.5);
    else
      EXPECT_LT(thrust[k], 2.5);
  }
}

TEST(Mixer, SaturationKeepsRollPitchThenYawHeadroomThenGivesUpThrust) {
  const airframe::AirframeParams af = test::make_quad();
  Mixer m(af);
  std::vector<double> thrust(4), cmd(4);
  const double max_total = m.max_total_thrust_n();
  // full thrust asked with roll and yaw: roll/pitch kept whole, yaw scaled, thrust lowered
  const Eigen::Vector3d tau(0.5, 0.0, 0.2);
  const MixerStatus st = m.mix(tau, max_total, thrust.data(), cmd.data());
  const Eigen::Vector4d w = wrench_of(m, thrust);
  EXPECT_DOUBLE_EQ(st.roll_pitch_scale, 1.0);
  EXPECT_NEAR(w[0], 0.5, kWrenchTol);
  EXPECT_LT(st.yaw_scale, 1.0);
  EXPECT_NEAR(w[2], 0.2 * st.yaw_scale, kWrenchTol);
  EXPECT_TRUE(st.limit_thrust_up);
  EXPECT_LT(w[3], max_total);
  for (int k = 0; k < 4; ++k) {
    EXPECT_GE(thrust[k], 0.0);
    EXPECT_LE(thrust[k], af.rotors[k].max_thrust_n + 1e-12);
  }
}

TEST(Mixer, FullThrustDemandLeavesYawOnlyItsHeadroom) {
  // test quad: max thrust per rotor M = 2 * 1.5 * g / 4 = 7.355 N, torque_coef 0.016 m, so a yaw
  // torque tau moves each rotor by tau / (4 * 0.016) = 15.625 tau (rotors 0, 1 down, 2, 3 up).
  // Asked: full collective 4 M and tau = 0.2 N m (3.125 N a rotor). Yaw keeps its headroom of 0.2 M
  // a rotor (scale 0.2 M / 3.125), the collective drops to what is left: rotors 2, 3 at M, rotors
  // 0, 1 at M - 2 * 0.2 M = 0.6 M, 3.2 M in all, instead of 2 M (hover) had yaw been given its
  // whole demand.
  const airframe::AirframeParams af = test::make_quad();
  Mixer m(af);
  std::vector<double> thrust(4), cmd(4);
  const double max_n = af.rotors[0].max_thrust_n;
  const MixerStatus st =
      m.mix(Eigen::Vector3d(0.0, 0.0, 0.2), 4.0 * max_n, thrust.data(), cmd.data());
  EXPECT_NEAR(thrust[0], 0.6 * max_n, kTolN);
  EXPECT_NEAR(thrust[1], 0.6 * max_n, kTolN);
  EXPECT_NEAR(thrust[2], max_n, kTolN);
  EXPECT_NEAR(thrust[3], max_n, kTolN);
  EXPECT_NEAR(st.yaw_scale, 0.2 * max_n / (15.625 * 0.2), kScaleTol);
  EXPECT_NEAR(st.thrust_n, 3.2 * max_n, kTolN);
  EXPECT_TRUE(st.limit_thrust_up);
  const Eigen::Vector4d w = wrench_of(m, thrust);
  EXPECT_NEAR(w[2], 0.2 * max_n * 4.0 * 0.016, kWrenchTol);
  EXPECT_NEAR(w[0], 0.0, kWrenchTol);
  EXPECT_NEAR(w[1], 0.0, kWrenchTol);
}

TEST(Mixer, YawBesideAMidCollectiveIsKeptWhole) {
  // at hover (each rotor at M / 2) the same 3.125 N a rotor fits: yaw and collective both whole
  const airframe::AirframeParams af = test::make_quad();
  Mixer m(af);
  std::vector<double> thrust(4), cmd(4);
  const double max_n = af.rotors[0].max_thrust_n;
  const MixerStatus st =
      m.mix(Eigen::Vector3d(0.0, 0.0, 0.2), 2.0 * max_n, thrust.data(), cmd.data());
  EXPECT_DOUBLE_EQ(st.yaw_scale, 1.0);
  EXPECT_NEAR(thrust[0], 0.5 * max_n - 3.125, kTolN);
  EXPECT_NEAR(thrust[2], 0.5 * max_n + 3.125, kTolN);
  EXPECT_NEAR(st.thrust_n, 2.0 * max_n, kTolN);
}

TEST(Mixer, ZeroThrustDemandIsRaisedToKeepAttitudeTorque) {
  Mixer m(test::make_quad());
  std::vector<double> thrust(4), cmd(4);
  const MixerStatus st = m.mix(Eigen::Vector3d(0.3, 0, 0), 0.0, thrust.data(), cmd.data());
  EXPECT_TRUE(st.limit_thrust_down);
  EXPECT_NEAR(wrench_of(m, thrust)[0], 0.3, kWrenchTol);
}

TEST(Mixer, ImpossibleRollIsScaledNotClipped) {
  // a roll torque beyond what the rotors can make: scaled down, direction kept, no yaw/pitch leak
  Mixer m(test::make_quad());
  std::vector<double> thrust(4), cmd(4);
  const MixerStatus st = m.mix(Eigen::Vector3d(50.0, 0, 0), 10.0, thrust.data(), cmd.data());
  const Eigen::Vector4d w = wrench_of(m, thrust);
  EXPECT_LT(st.roll_pitch_scale, 1.0);
  EXPECT_NEAR(w[0], 50.0 * st.roll_pitch_scale, kWrenchTol);
  EXPECT_NEAR(w[1], 0.0, kWrenchTol);
  EXPECT_NEAR(w[2], 0.0, kWrenchTol);
}

TEST(Mixer, MotorCommandInvertsSquareLaw) {
  const airframe::AirframeParams af = test::make_hexa();
  Mixer m(af);
  std::vector<double> thrust(6), cmd(6);
  m.mix(Eigen::Vector3d(0.5, -0.3, 0.1), 50.0, thrust.data(), cmd.data());
  // plant: thrust = max * speed^2, so speed = cmd must give the thrust back
  for (int k = 0; k < 6; ++k)
    EXPECT_NEAR(af.rotors[k].max_thrust_n * cmd[k] * cmd[k], thrust[k], kTolN);
}

TEST(Mixer, RejectsUnusableLayouts) {
  airframe::AirframeParams af = test::make_quad();
  af.rotors.resize(2);
  EXPECT_THROW(Mixer{af}, std::invalid_argument);
  af.rotors.clear();
  EXPECT_THROW(Mixer{af}, std::invalid_argument);
}

}  // namespace
}  // namespace uavsim::server::fc
