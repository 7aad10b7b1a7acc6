// The A2A radio model's cost (server/src/radio/radio_model.hpp): N vehicles on a 20 m grid, all in
// range, each broadcasting a 50-byte frame at 10 Hz, stepped at 1 kHz for 1 s of sim time per
// iteration. Reports frames sent/s and deliveries/s (each broadcast reaches N - 1 receivers).
#include <benchmark/benchmark.h>

#include <cmath>
#include <vector>

#include "radio/radio_model.hpp"

namespace {

using uavsim::server::radio::Delivery;
using uavsim::server::radio::kBroadcast;
using uavsim::server::radio::RadioConfig;
using uavsim::server::radio::RadioModel;

void run_radio(benchmark::State& state, bool collisions) {
  const auto n = static_cast<size_t>(state.range(0));
  constexpr double kStep_s = 0.001;
  RadioConfig c;
  c.range_m = 1000.0;
  c.collisions = collisions;
  c.loss_probability = 0.1;
  std::vector<Eigen::Vector3d> pos;
  const auto side = static_cast<size_t>(std::ceil(std::sqrt(static_cast<double>(n))));
  for (size_t i = 0; i < n; ++i) pos.emplace_back(20.0 * (i % side), 20.0 * (i / side), 10.0);
  const std::vector<uint8_t> frame(50, 0x5A);
  int64_t frames = 0, deliveries = 0;
  std::vector<Delivery> out;
  for (auto _ : state) {
    RadioModel m(n, c, 1, kStep_s);
    for (int k = 0; k < 1000; ++k) {
      const double t = k * kStep_s;
      // vehicle i sends at step (i * 100 / n) of every 100 ms: spread evenly over the period (10
      // vehicles: 10 ms apart, no overlap; 100: 1 ms apart, under the 1.79 ms airtime, so they
      // collide)
      for (size_t i = 0; i < n; ++i) {
        if (static_cast<size_t>(k % 100) != i * 100 / n) continue;
        m.send(i, kBroadcast, frame, t);
        ++frames;
      }
      out.clear();
      m.step(t, pos, &out);
      deliveries += static_cast<int64_t>(out.size());
    }
    benchmark::DoNotOptimize(out.data());
  }
  state.SetItemsProcessed(frames);
  state.counters["deliveries/s"] =
      benchmark::Counter(static_cast<double>(deliveries), benchmark::Counter::kIsRate);
}

void BM_RadioBroadcast(benchmark::State& state) { run_radio(state, false); }
void BM_RadioBroadcastCollisions(benchmark::State& state) { run_radio(state, true); }

BENCHMARK(BM_RadioBroadcast)->Arg(10)->Arg(100)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_RadioBroadcastCollisions)->Arg(10)->Arg(100)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
