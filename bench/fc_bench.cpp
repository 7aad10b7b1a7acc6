// BM_FlightControllerUpdate: one FC control step (sensors, estimator, mode logic, full cascade and
// mixer) for a quad taking off in GUIDED, the hot path of a many-vehicle simulation.
#include <benchmark/benchmark.h>

#include <cmath>
#include <vector>

#include "fc/flight_controller.hpp"

namespace {

using namespace uavsim::server;

airframe::AirframeParams make_quad() {
  airframe::AirframeParams a;
  a.frame = "quad";
  a.mass_kg = 1.5;
  a.inertia_body_kgm2 = Eigen::Vector3d(0.029, 0.029, 0.055).asDiagonal();
  const double r = 0.275 / std::sqrt(2.0);
  const double xs[4] = {r, -r, r, -r}, ys[4] = {-r, r, r, -r};
  const int dirs[4] = {1, 1, -1, -1};
  for (int k = 0; k < 4; ++k) {
    airframe::RotorParams rp;
    rp.position_body_m = Eigen::Vector3d(xs[k], ys[k], 0.0);
    rp.spin_dir = dirs[k];
    rp.max_thrust_n = 2.0 * a.mass_kg * 9.80665 / 4.0;
    rp.torque_coef_m = 0.016;
    rp.time_const_s = 0.03;
    a.rotors.push_back(rp);
  }
  return a;
}

// A hexa (S900 class): six rotors, so the lost-motor monitor runs on every step too.
airframe::AirframeParams make_hexa() {
  airframe::AirframeParams a;
  a.frame = "hexa";
  a.mass_kg = 6.8;
  a.inertia_body_kgm2 = Eigen::Vector3d(0.24, 0.24, 0.43).asDiagonal();
  for (int k = 0; k < 6; ++k) {
    const double ang = (30.0 + 60.0 * k) * 3.14159265358979323846 / 180.0;
    airframe::RotorParams rp;
    rp.position_body_m = Eigen::Vector3d(0.45 * std::cos(ang), 0.45 * std::sin(ang), 0.0);
    rp.spin_dir = (k % 2 == 0) ? 1 : -1;
    rp.max_thrust_n = 2.0 * a.mass_kg * 9.80665 / 6.0;
    rp.torque_coef_m = 0.02;
    rp.time_const_s = 0.05;
    a.rotors.push_back(rp);
  }
  return a;
}

void run_update_bench(benchmark::State& state, const airframe::AirframeParams& af) {
  fc::FlightController controller(af, 1);
  fc::TruthState truth;
  airframe::BatteryState battery;
  std::vector<double> cmd(af.rotors.size());
  double t = 0.0;
  // warm-up: converge the estimator, arm in GUIDED and start a take-off so the whole cascade runs
  for (int k = 0; k < 1500; ++k, t += 0.002) controller.update(t, truth, battery, cmd.data());
  controller.set_mode(fc::Mode::kGuided);
  controller.arm(false);
  controller.takeoff(1000.0);  // far away: stays in the climbing cascade for the whole benchmark
  for (auto _ : state) {
    controller.update(t, truth, battery, cmd.data());
    benchmark::DoNotOptimize(cmd.data());
    t += 0.002;
  }
  state.SetItemsProcessed(state.iterations());
}

void BM_FlightControllerUpdate(benchmark::State& state) { run_update_bench(state, make_quad()); }
BENCHMARK(BM_FlightControllerUpdate);

void BM_FlightControllerUpdateHexa(benchmark::State& state) { run_update_bench(state, make_hexa()); }
BENCHMARK(BM_FlightControllerUpdateHexa);

}  // namespace

BENCHMARK_MAIN();
