// The whole simulation per vehicle-step beside bare mj_step on the same world (issue 17's
// benchmark). Worlds: N lean quads (collision="lean") on a 4 m grid, started on the ground.
//   BM_Sim/parked/N     all parked on the ground (disarmed, at rest): Simulation::step (flight
//   controllers
//                       at 500 Hz with sensors and estimator, motors, parking, contact checks)
//   BM_MjStep/parked/N  mj_step alone on the same world and state
//   BM_Sim/hover/N      all took off from the ground (launched as fast as the constraint rows
//   allow) and
//                       hover 5 m above their grid points: a formation
//   BM_MjStep/hover/N   mj_step alone on the same world and state (rotor wrenches of the last step)
//   BM_BareMjStep/full|lean/N  free-flying quads held by a constant m g in qfrc_applied, 10 m up:
//   the
//                       cost of the collision set alone
//   BM_Formation/N/shards:S/threads:T  N quads start parked on the ground, all take off (in waves that the
//                       constraint rows of each physics shard hold) and hover 5 m up in formation, in S
//                       physics shards stepped by T threads (physics/world.hpp); wall-clock timed.
//                       Counters: us_per_vehicle_step and realtime_x on the wall clock, cpu_realtime_x
//                       (sim seconds per CPU second of the whole process), physics_us_per_vehicle_step
//                       (World::step alone: every shard's mj_step, on the pool), fc_us_per_vehicle_step
//                       (the rest of Simulation::step: flight controllers, motors, wrenches, contact
//                       checks), startup_s, rss_mb, flying.
// Counters: us_per_vehicle_step (wall), realtime_x, startup_s (compose + load + Simulation), rss_mb
// (the process after start-up), flying. items/s = vehicle-steps per second: compare rows of one run
// only.
#include <benchmark/benchmark.h>
#include <mujoco/mujoco.h>

#include <time.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "bench_fleet.hpp"
#include "physics/world.hpp"
#include "sim/simulation.hpp"

namespace {

using namespace uavsim::server;
using uavsim::bench::launch_all;
using uavsim::bench::launch_all_sharded;
using uavsim::bench::load;

enum Kind { kParked = 0, kHover = 1 };

double cpu_s() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

double rss_mb() {
  std::ifstream in("/proc/self/status");
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("VmRSS:", 0) == 0) return std::stod(line.substr(6)) / 1024.0;
  }
  return 0.0;
}

struct Rig {
  int kind = -1;
  int n = 0;
  std::unique_ptr<sim::Simulation> sim;
  double startup_s = 0.0;
  double rss_mb = 0.0;
  size_t flying = 0;
};

Rig& rig(int kind, int n) {
  static Rig r;
  if (r.kind == kind && r.n == n) return r;
  r = Rig{};
  const auto t0 = std::chrono::steady_clock::now();
  r.sim = std::make_unique<sim::Simulation>(load(n, 0.0, "lean"), sim::SimConfig{});
  r.startup_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  r.rss_mb = rss_mb();
  r.kind = kind;
  r.n = n;
  sim::Simulation& s = *r.sim;
  while (s.time_s() < 20.0 && !s.fc(0).prearm_ok()) s.step();
  if (kind == kHover) launch_all(s);
  r.flying = uavsim::bench::flying(s);
  return r;
}

void report(benchmark::State& state, const Rig& r, double dt_s) {
  state.SetItemsProcessed(state.iterations() * r.n);
  state.counters["us_per_vehicle_step"] =
      benchmark::Counter(static_cast<double>(state.iterations() * r.n) * 1e-6,
                         benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  state.counters["realtime_x"] = benchmark::Counter(static_cast<double>(state.iterations()) * dt_s,
                                                    benchmark::Counter::kIsRate);
  state.counters["startup_s"] = r.startup_s;
  state.counters["rss_mb"] = r.rss_mb;
  state.counters["flying"] = static_cast<double>(r.flying);
  state.counters["parked"] = static_cast<double>(r.sim->world().parked_count());
  state.counters["overflows"] = r.sim->world().buffer_overflows();
}

void BM_Sim(benchmark::State& state, int kind) {
  Rig& r = rig(kind, static_cast<int>(state.range(0)));
  for (auto _ : state) r.sim->step();
  report(state, r, r.sim->physics_dt_s());
}

// mj_step on the rig's own world and state, restored every kBatch steps (MuJoCo 2.2 has no
// mj_getState: time, qpos, qvel, act) so that the state being measured does not drift away
void BM_MjStep(benchmark::State& state, int kind) {
  constexpr int kBatch = 200;
  Rig& r = rig(kind, static_cast<int>(state.range(0)));
  physics::World& world = r.sim->world();
  const mjModel* m = world.model();
  mjData* d = world.data();
  const double time0 = d->time;
  const std::vector<mjtNum> qpos0(d->qpos, d->qpos + m->nq), qvel0(d->qvel, d->qvel + m->nv),
      act0(d->act, d->act + m->na);
  auto restore = [&] {
    d->time = time0;
    std::copy(qpos0.begin(), qpos0.end(), d->qpos);
    std::copy(qvel0.begin(), qvel0.end(), d->qvel);
    std::copy(act0.begin(), act0.end(), d->act);
    mj_forward(m, d);
  };
  int k = 0;
  for (auto _ : state) {
    mj_step(m, d);
    if (++k == kBatch) {
      state.PauseTiming();
      k = 0;
      restore();
      state.ResumeTiming();
    }
  }
  restore();
  report(state, r, m->opt.timestep);
}

void BM_BareMjStep(benchmark::State& state, const char* collision) {
  const int n = static_cast<int>(state.range(0));
  auto world = load(n, 10.0, collision);
  // hold every quad where it starts, 10 m up, with a constant force m*g
  for (size_t i = 0; i < world->vehicles().size(); ++i) {
    airframe::Wrench w;
    w.force_enu_n.z() = world->vehicles()[i].airframe.mass_kg * 9.81;
    world->apply_wrench(i, w);
  }
  for (int i = 0; i < 100; ++i) world->step();
  for (auto _ : state) world->step();
  state.SetItemsProcessed(state.iterations() * n);
  state.counters["us_per_vehicle_step"] =
      benchmark::Counter(static_cast<double>(state.iterations() * n) * 1e-6,
                         benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  state.counters["realtime_x"] = benchmark::Counter(
      static_cast<double>(state.iterations()) * world->timestep_s(), benchmark::Counter::kIsRate);
}

void BM_Formation(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const int shards = static_cast<int>(state.range(1));
  const int threads = static_cast<int>(state.range(2));
  Rig r;
  const auto t0 = std::chrono::steady_clock::now();
  r.sim = std::make_unique<sim::Simulation>(load(n, 0.0, "lean", physics::ShardOptions{shards, threads}),
                                            sim::SimConfig{});
  r.startup_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  r.rss_mb = rss_mb();
  r.n = n;
  sim::Simulation& s = *r.sim;
  while (s.time_s() < 20.0 && !s.fc(0).prearm_ok()) s.step();
  launch_all_sharded(s, s.world().model()->njmax, 5.0);
  r.flying = uavsim::bench::flying(s);

  // physics alone (every shard's step on the pool, the last rotor wrenches held), then the whole step
  constexpr int kPhysicsSteps = 200;
  const auto p0 = std::chrono::steady_clock::now();
  for (int i = 0; i < kPhysicsSteps; ++i) s.world().step();
  const double physics_us =
      1e6 * std::chrono::duration<double>(std::chrono::steady_clock::now() - p0).count() / (kPhysicsSteps * n);
  const double c0 = cpu_s();
  const auto w0 = std::chrono::steady_clock::now();
  for (auto _ : state) s.step();
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - w0).count();
  const double cpu = cpu_s() - c0;
  report(state, r, s.physics_dt_s());
  const double sim_s = static_cast<double>(state.iterations()) * s.physics_dt_s();
  const double step_us = 1e6 * wall / (static_cast<double>(state.iterations()) * n);
  state.counters["cpu_realtime_x"] = sim_s / cpu;
  state.counters["physics_us_per_vehicle_step"] = physics_us;
  state.counters["fc_us_per_vehicle_step"] = step_us - physics_us;
  state.counters["shards"] = shards;
  state.counters["threads"] = s.world().thread_count();
}

// each world's two benchmarks next to each other, so that one warmed-up rig serves both
const int registered = [] {
  for (int n : {1, 10, 100, 300, 1000, 3000}) {
    benchmark::RegisterBenchmark("BM_Sim/parked", BM_Sim, kParked)
        ->Arg(n)
        ->Unit(benchmark::kMicrosecond);
    benchmark::RegisterBenchmark("BM_MjStep/parked", BM_MjStep, kParked)
        ->Arg(n)
        ->Unit(benchmark::kMicrosecond);
  }
  for (int n : {1, 10, 100, 300, 1000}) {
    benchmark::RegisterBenchmark("BM_Sim/hover", BM_Sim, kHover)
        ->Arg(n)
        ->Unit(benchmark::kMicrosecond);
    benchmark::RegisterBenchmark("BM_MjStep/hover", BM_MjStep, kHover)
        ->Arg(n)
        ->Unit(benchmark::kMicrosecond);
  }
  for (int n : {1, 100, 1000}) {
    benchmark::RegisterBenchmark("BM_BareMjStep/full", BM_BareMjStep, "full")
        ->Arg(n)
        ->Unit(benchmark::kMicrosecond);
    benchmark::RegisterBenchmark("BM_BareMjStep/lean", BM_BareMjStep, "lean")
        ->Arg(n)
        ->Unit(benchmark::kMicrosecond);
  }
  for (int n : {100, 1000}) {
    for (const auto& [shards, threads] : {std::pair{1, 1}, std::pair{2, 1}, std::pair{2, 2}}) {
      benchmark::RegisterBenchmark("BM_Formation", BM_Formation)
          ->Args({n, shards, threads})
          ->ArgNames({"", "shards", "threads"})
          ->UseRealTime()
          ->Unit(benchmark::kMicrosecond);
    }
  }
  // 3000 quads: 4 shards of 750 (one model would need a constraint buffer MuJoCo 2.2 cannot allocate)
  for (int threads : {1, 2}) {
    benchmark::RegisterBenchmark("BM_Formation", BM_Formation)
        ->Args({3000, 4, threads})
        ->ArgNames({"", "shards", "threads"})
        ->UseRealTime()
        ->Unit(benchmark::kMicrosecond);
  }
  return 0;
}();

}  // namespace

BENCHMARK_MAIN();
