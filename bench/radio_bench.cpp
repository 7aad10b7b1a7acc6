// The A2A radio's cost (server/src/radio/): N vehicles on a 20 m grid, all in range, each
// broadcasting a 50-byte frame at 10 Hz, stepped at 1 kHz for 1 s of sim time per iteration.
// Reports frames sent/s and deliveries/s (each broadcast reaches N - 1 receivers); the per-backend
// benchmarks (BM_RadioChannel) also the wall time per frame and per step and the ns3 helper's
// resident memory, and BM_Ns3HelperStartup what starting the helper for N radios costs.
// docs/results/radio.md has the figures.
#include <benchmark/benchmark.h>

#include <cmath>
#include <fstream>
#include <string>
#include <vector>

#include "radio/ns3_channel.hpp"
#include "radio/radio_model.hpp"
#include "radio/sim_radio.hpp"

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

// One client flooding the radio (issue 29: ~7000 radio_send a second from one client slowed the
// clock to 0.23x): vehicle 0 of 5 sends range(0) frames of 16 bytes every 1 ms step for range(1)
// s of sim time, against a channel that carries (16 + 6) * 8 / 250000 = 0.704 ms a frame, at
// most 1420 a second. 1 frame a step is under that; 7 a step (7000/s) is the flood. Reports sim
// seconds per wall second, the frames accepted, refused (queue_full) and delivered, and the
// sender's backlog (accepted, not yet on air) at the end.
void BM_RadioFlood(benchmark::State& state) {
  constexpr size_t kVehicles = 5;
  constexpr double kStep_s = 0.001;
  const auto per_step = static_cast<int>(state.range(0));
  const auto steps = static_cast<int>(state.range(1) * 1000);
  std::vector<Eigen::Vector3d> pos;
  for (size_t i = 0; i < kVehicles; ++i) pos.emplace_back(20.0 * i, 0.0, 10.0);
  const std::vector<uint8_t> frame(16, 0x5A);
  int64_t accepted = 0, refused = 0, deliveries = 0;
  double sim_s = 0.0;
  size_t backlog = 0;
  std::vector<Delivery> out;
  for (auto _ : state) {
    RadioModel m(kVehicles, RadioConfig{}, 1, kStep_s);
    for (int k = 0; k < steps; ++k) {
      const double t = k * kStep_s;
      for (int f = 0; f < per_step; ++f) {
        if (m.send(0, kBroadcast, frame, t).seq) {
          ++accepted;
        } else {
          ++refused;
        }
      }
      out.clear();
      m.step(t, pos, &out);
      deliveries += static_cast<int64_t>(out.size());
    }
    sim_s += steps * kStep_s;
    backlog = m.queued(0);
  }
  state.counters["sim_s/wall_s"] = benchmark::Counter(sim_s, benchmark::Counter::kIsRate);
  state.counters["accepted"] = static_cast<double>(accepted);
  state.counters["refused"] = static_cast<double>(refused);
  state.counters["deliveries"] = static_cast<double>(deliveries);
  state.counters["backlog"] = static_cast<double>(backlog);
}
BENCHMARK(BM_RadioFlood)
    ->Args({1, 4})
    ->Args({7, 4})
    ->Iterations(1)
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);

namespace radio = uavsim::server::radio;

// a process's resident memory, MB (VmRSS of /proc/PID/status), 0 if unreadable
double rss_mb(const std::string& pid) {
  std::ifstream in("/proc/" + pid + "/status");
  std::string key;
  while (in >> key) {
    if (key == "VmRSS:") {
      double kb = 0.0;
      in >> kb;
      return kb / 1024.0;
    }
  }
  return 0.0;
}

radio::BackendOptions backend_options(radio::Backend b) {
  radio::BackendOptions o;
  o.backend = b;
#ifdef UAVSIM_NS3_HELPER_PATH
  o.ns3.helper_path = UAVSIM_NS3_HELPER_PATH;
#endif
  return o;
}

// the same load on either backend (the simple model with collisions and the 11-byte MAC header,
// as ns-3 has them)
void run_channel(benchmark::State& state, radio::Backend backend) {
  const auto n = static_cast<size_t>(state.range(0));
  constexpr double kStep_s = 0.001;
  constexpr int kSteps = 1000;
  RadioConfig c;
  c.range_m = 1000.0;
  c.collisions = true;
  c.mac_header_bytes = 11;
  std::vector<Eigen::Vector3d> pos;
  const auto side = static_cast<size_t>(std::ceil(std::sqrt(static_cast<double>(n))));
  for (size_t i = 0; i < n; ++i) pos.emplace_back(20.0 * (i % side), 20.0 * (i / side), 10.0);
  const std::vector<uint8_t> frame(50, 0x5A);
  int64_t frames = 0, deliveries = 0, steps = 0;
  double helper_rss = 0.0;
  std::vector<Delivery> out;
  for (auto _ : state) {
    state.PauseTiming();
    auto ch = radio::make_channel(backend_options(backend), n, c, 1, kStep_s);
    state.ResumeTiming();
    for (int k = 0; k < kSteps; ++k) {
      const double t = k * kStep_s;
      for (size_t i = 0; i < n; ++i) {
        if (static_cast<size_t>(k % 100) != i * 100 / n) continue;
        ch->send(i, kBroadcast, frame, t);
        ++frames;
      }
      out.clear();
      ch->step(t, pos, &out);
      deliveries += static_cast<int64_t>(out.size());
      ++steps;
    }
    state.PauseTiming();
    if (auto* ns3 = dynamic_cast<radio::Ns3Channel*>(ch.get())) {
      helper_rss = rss_mb(std::to_string(ns3->helper_pid()));
      if (!ns3->failure().empty()) state.SkipWithError(ns3->failure().c_str());
    }
    ch.reset();
    state.ResumeTiming();
  }
  state.SetItemsProcessed(frames);
  state.counters["deliveries/s"] =
      benchmark::Counter(static_cast<double>(deliveries), benchmark::Counter::kIsRate);
  state.counters["us/frame"] =
      benchmark::Counter(static_cast<double>(frames) * 1e-6,
                         benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  state.counters["us/step"] = benchmark::Counter(
      static_cast<double>(steps) * 1e-6, benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  state.counters["helper_rss_mb"] = helper_rss;
  state.counters["server_rss_mb"] = rss_mb("self");
}

void BM_RadioChannelSimple(benchmark::State& state) { run_channel(state, radio::Backend::kSimple); }
// wall time: the ns3 backend's work is in the helper process, which the bench's CPU time misses
BENCHMARK(BM_RadioChannelSimple)
    ->Arg(10)
    ->Arg(25)
    ->Arg(100)
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);

#ifdef UAVSIM_NS3_HELPER_PATH
void BM_RadioChannelNs3(benchmark::State& state) { run_channel(state, radio::Backend::kNs3); }
BENCHMARK(BM_RadioChannelNs3)
    ->Arg(10)
    ->Arg(25)
    ->Arg(100)
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);

// spawning the helper and building its ns-3 world of N nodes (ending it is not timed)
void BM_Ns3HelperStartup(benchmark::State& state) {
  const auto n = static_cast<size_t>(state.range(0));
  for (auto _ : state) {
    auto ch =
        radio::make_channel(backend_options(radio::Backend::kNs3), n, RadioConfig{}, 1, 0.001);
    benchmark::DoNotOptimize(ch.get());
    state.PauseTiming();
    ch.reset();
    state.ResumeTiming();
  }
}
BENCHMARK(BM_Ns3HelperStartup)
    ->Arg(10)
    ->Arg(100)
    ->Arg(1000)
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);
#endif

}  // namespace

BENCHMARK_MAIN();
