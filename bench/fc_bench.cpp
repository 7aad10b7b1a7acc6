// BM_FlightControllerUpdate: one FC control step (sensors, estimator, mode logic, full cascade and
// mixer) for a quad taking off in GUIDED, the hot path of a many-vehicle simulation.
#include <benchmark/benchmark.h>

#include <cmath>
#include <vector>

#include "fc/flight_controller.hpp"
// the fc tests' quad and hexa, so the benchmark measures the vehicles the tests fly
#include "../tests/server/fc/test_airframes.hpp"

namespace {

using namespace uavsim::server;
using fc::test::make_hexa;
using fc::test::make_quad;

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
