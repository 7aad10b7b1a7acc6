// Field conditions in the closed loop (sim/field_conditions.hpp): a quad hovering in wind, battery
// sag, the estimator under field sensor errors, and seeded determinism.
#include <gtest/gtest.h>

#include <cmath>

#include "sim_fixture.hpp"
#include "uavsim/common/angles.hpp"

namespace uavsim::server::sim {
namespace {

using testing::take_off;

constexpr double kG = 9.81;
constexpr double kVoltTol_V = 1e-9;
constexpr double kExactTol = 1e-12;

std::unique_ptr<Simulation> make_field_sim(const FieldConditions& field, uint64_t seed = 1) {
  physics::ComposeOptions o;
  o.models_dir = UAVSIM_MODELS_DIR;
  SimConfig c;
  c.seed = seed;
  c.field = field;
  return std::make_unique<Simulation>(
      physics::World::load(std::string(UAVSIM_MODELS_DIR) + "/worlds/empty.xml", o), c);
}

// tilt of the body z axis from vertical, and its horizontal direction (ENU)
double tilt_rad(const Eigen::Quaterniond& q) {
  const Eigen::Vector3d z = q * Eigen::Vector3d::UnitZ();
  return std::acos(std::clamp(z.z(), -1.0, 1.0));
}

TEST(FieldWind, HoveringQuadHoldsPositionAndTiltsIntoTheWind) {
  FieldConditions field;
  field.wind.speed_m_s = 5.0;
  field.wind.from_deg = 270.0;  // from the west: the air moves towards +x (east)
  auto sim = make_field_sim(field);
  take_off(*sim, 5.0);
  const Eigen::Vector3d hold = sim->truth(0).position_enu_m;
  testing::goto_enu(*sim, Eigen::Vector3d(0.0, 0.0, hold.z()));
  sim->run_until(sim->time_s() +
                 15.0);  // settle (the position loop's integrator takes up the drag)

  // over 10 s: position error and the mean tilt
  double max_err_m = 0.0, tilt_sum = 0.0, lean_x_sum = 0.0;
  int n = 0;
  const double end_s = sim->time_s() + 10.0;
  while (sim->time_s() < end_s) {
    sim->step();
    const fc::TruthState t = sim->truth(0);
    max_err_m =
        std::max(max_err_m, (t.position_enu_m - Eigen::Vector3d(0.0, 0.0, hold.z())).norm());
    tilt_sum += tilt_rad(t.q_enu_body);
    lean_x_sum += (t.q_enu_body * Eigen::Vector3d::UnitZ()).x();
    ++n;
  }
  EXPECT_LT(max_err_m, 0.5) << "position hold in a steady 5 m/s wind";

  // steady hover in wind V: the thrust's horizontal part balances the drag, its vertical part
  // the weight:
  //   tan(theta) = D / (m g),  D = lin V + quad V^2
  //   (body x; the body z part is second order in theta)
  //   quad.xml: D = 0.10 * 5 + 0.05 * 25 = 1.75 N; m g = 1.5 * 9.81 = 14.7 N
  //   theta = atan(0.119) = 6.8 deg
  const airframe::AirframeParams& a = sim->airframe(0);
  const double v = 5.0;
  const double drag_n = a.drag_lin_n_per_m_s.x() * v + a.drag_quad_n_per_m2_s2.x() * v * v;
  const double expected_rad = std::atan(drag_n / (a.mass_kg * kG));
  constexpr double kTiltTolerance_rad = 0.5 * common::kPi / 180.0;
  EXPECT_NEAR(tilt_sum / n, expected_rad, kTiltTolerance_rad);
  RecordProperty("tilt_deg", std::to_string(tilt_sum / n * 180.0 / common::kPi));
  RecordProperty("expected_tilt_deg", std::to_string(expected_rad * 180.0 / common::kPi));
  RecordProperty("max_position_error_m", std::to_string(max_err_m));
  // into the wind: thrust leans west, against the air moving east
  EXPECT_LT(lean_x_sum / n, -0.9 * std::sin(expected_rad));
}

TEST(FieldWind, HoverInFieldTurbulenceStaysWithinAMetre) {
  // the field defaults (4 m/s, 1 m/s turbulence, gusts; GPS bias: judged on truth against the
  // estimate's own hold point, so the GPS error does not count here) for 60 s
  FieldConditions field = field_conditions(Realism::kField);
  field.sensor_params.clear();
  field.wind.gust_rate_hz = 0.0;
  auto sim = make_field_sim(field, 4);
  take_off(*sim, 5.0);
  const Eigen::Vector3d hold = sim->truth(0).position_enu_m;
  testing::goto_enu(*sim, hold);
  sim->run_until(sim->time_s() + 10.0);
  double max_err_m = 0.0, sum2 = 0.0;
  int n = 0;
  const double end_s = sim->time_s() + 60.0;
  while (sim->time_s() < end_s) {
    sim->step();
    const double e = (sim->truth(0).position_enu_m - hold).head<2>().norm();
    max_err_m = std::max(max_err_m, e);
    sum2 += e * e;
    ++n;
  }
  RecordProperty("rms_m", std::to_string(std::sqrt(sum2 / n)));
  RecordProperty("max_m", std::to_string(max_err_m));
  EXPECT_LT(max_err_m, 1.0);
}

TEST(FieldWind, SameSeedSameFlightDifferentSeedDifferent) {
  FieldConditions field = field_conditions(Realism::kField);
  auto fly = [&](uint64_t seed) {
    auto sim = make_field_sim(field, seed);
    take_off(*sim, 3.0);
    sim->run_until(sim->time_s() + 5.0);
    return sim->state_hash();
  };
  EXPECT_EQ(fly(7), fly(7));
  EXPECT_NE(fly(7), fly(8));
}

TEST(FieldWind, ResetRestartsTheWindFromTheSeed) {
  FieldConditions field = field_conditions(Realism::kField);
  auto sim = make_field_sim(field, 3);
  std::vector<double> first;
  for (int k = 0; k < 2000; ++k) {
    sim->step();
    first.push_back(sim->wind().velocity_enu_m_s().x());
  }
  sim->reset(3);
  for (int k = 0; k < 2000; ++k) {
    sim->step();
    ASSERT_EQ(sim->wind().velocity_enu_m_s().x(), first[static_cast<size_t>(k)]) << "step " << k;
  }
}

TEST(FieldBattery, SagUnderLoadLowersTheAvailableThrust) {
  // a fresh 3S pack (12.6 V open circuit), R = 20 mOhm: at power P the terminal voltage is
  //   V = (V_oc + sqrt(V_oc^2 - 4 R P)) / 2;  full thrust scales with (V / 12.6)^2
  airframe::AirframeParams a;
  a.rotors.resize(4);
  a.battery.internal_resistance_ohm = 0.02;
  auto scale_at = [&](double thrust_each_n) {
    airframe::BatteryState b;
    const double thrust[4] = {thrust_each_n, thrust_each_n, thrust_each_n, thrust_each_n};
    airframe::step_battery(a, thrust, 0.002, &b);
    return std::make_pair(b.voltage_v, airframe::battery_thrust_scale(a, b));
  };
  const auto [v_light, s_light] = scale_at(1.0);
  const auto [v_hover, s_hover] = scale_at(3.7);  // 1.5 kg / 4
  const auto [v_full, s_full] = scale_at(9.0);    // near full throttle
  EXPECT_GT(v_light, v_hover);
  EXPECT_GT(v_hover, v_full);
  EXPECT_GT(s_light, s_hover);
  EXPECT_GT(s_hover, s_full);
  // the voltage the quadratic gives: V_oc - V = R I = R P / V
  airframe::BatteryState b;
  const double thrust[4] = {9.0, 9.0, 9.0, 9.0};
  airframe::step_battery(a, thrust, 0.002, &b);
  EXPECT_NEAR(12.6 - b.voltage_v, 0.02 * b.current_a, kVoltTol_V);
  EXPECT_NEAR(s_full, (b.voltage_v / 12.6) * (b.voltage_v / 12.6), kExactTol);
  // without resistance: the ideal world's thrust does not depend on the battery
  a.battery.internal_resistance_ohm = 0.0;
  EXPECT_EQ(scale_at(9.0).second, 1.0);
}

TEST(FieldBattery, SagUnderLoadNeedsMoreMotorCommandToHover) {
  // hover thrust is the weight either way; with sag the rotors make less per command, so the mean
  // command rises by about 1 / sqrt(scale) (thrust ~ command^2 at the rotor)
  auto hover = [](double resistance_ohm, double* voltage_v) {
    FieldConditions field;
    field.battery_resistance_ohm = resistance_ohm;
    auto sim = make_field_sim(field);
    take_off(*sim, 3.0);
    sim->run_until(sim->time_s() + 5.0);
    double cmd = 0.0;
    for (double c : sim->runtime(0).motor_cmd) cmd += c;
    *voltage_v = sim->runtime(0).battery.voltage_v;
    return cmd / static_cast<double>(sim->runtime(0).motor_cmd.size());
  };
  double v_ideal = 0.0, v_sag = 0.0;
  const double cmd_ideal = hover(0.0, &v_ideal);
  const double cmd_sag = hover(0.05, &v_sag);
  // hover power ~ 200 W: I ~ 17 A, 0.05 ohm sags ~ 0.85 V
  EXPECT_LT(v_sag, v_ideal - 0.5);
  RecordProperty("hover_voltage_v", std::to_string(v_ideal) + " -> " + std::to_string(v_sag));
  RecordProperty("hover_command", std::to_string(cmd_ideal) + " -> " + std::to_string(cmd_sag));
  EXPECT_GT(cmd_sag, cmd_ideal * 1.02);
}

TEST(FieldSensors, EstimateWandersWithTheGpsBiasAndRtkHoldsCentimetres) {
  // a quad resting on the ground for 150 s: the estimated horizontal position error is GPS's
  auto rms_error = [](double rtk) {
    FieldConditions field = field_conditions(Realism::kField);
    field.wind = {};
    field.wind_from_seeded = false;
    field.sensor_params.emplace_back("SIM_GPS_RTK", rtk);
    auto sim = make_field_sim(field, 5);
    double sum2 = 0.0;
    int n = 0;
    while (sim->time_s() < 150.0) {
      sim->run_until(sim->time_s() + 0.1);
      if (sim->time_s() < 20.0) continue;  // the estimator's start
      const Eigen::Vector2d e =
          (sim->fc(0).estimate().position_enu_m - sim->truth(0).position_enu_m).head<2>();
      sum2 += e.squaredNorm();
      ++n;
    }
    return std::sqrt(sum2 / n);
  };
  // field: horizontal bias sd 0.7 m per axis (one correlation time here: loosely), white 0.15 m
  const double field_rms = rms_error(0.0);
  RecordProperty("field_rms_m", std::to_string(field_rms));
  EXPECT_GT(field_rms, 0.3);
  EXPECT_LT(field_rms, 3.0);
  // RTK: 1 cm per axis white noise, filtered by the estimator: well under 5 cm
  const double rtk_rms = rms_error(1.0);
  RecordProperty("rtk_rms_m", std::to_string(rtk_rms));
  EXPECT_LT(rtk_rms, 0.05);
}

}  // namespace
}  // namespace uavsim::server::sim
