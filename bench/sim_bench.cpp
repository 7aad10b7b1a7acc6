// Physics + flight control per vehicle-step, beside bare mj_step on the same world (issue 2's benchmark).
//   BM_BareMjStep/N      N hovering quads, constant hover force written into qfrc_applied, mj_step only
//   BM_SimStep/N         N quads hovering under their flight controllers: Simulation::step (motors, wrench,
//                        FC at 500 Hz with sensors and estimator, mj_step, contact checks)
//   BM_MjStepSameState/N mj_step alone on BM_SimStep's own world and state: the like-for-like baseline
// items/s = vehicle-steps per second; compare the two at the same N in one run.
#include <benchmark/benchmark.h>
#include <mujoco/mujoco.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "physics/world.hpp"
#include "sim/simulation.hpp"

namespace {

using namespace uavsim::server;

std::string grid_world(int n) {
  // the most square grid of exactly n: rows = the largest divisor of n not above sqrt(n)
  int rows = 1;
  for (int r = 1; r * r <= n; ++r) {
    if (n % r == 0) rows = r;
  }
  const int cols = n / rows;
  const std::string path =
      (std::filesystem::temp_directory_path() / ("uavsim_bench_grid" + std::to_string(n) + ".xml")).string();
  // the vehicles start 10 m up (see BM_SimStep): no ground contacts, which for 1000 grounded quads
  // would need more constraint rows than MuJoCo 2.2's dense njmax x njmax buffer allows
  std::ofstream(path) << "<mujoco><compiler angle=\"radian\"/><option timestep=\"0.001\"/>"
                      << "<worldbody><geom name=\"ground\" type=\"plane\" size=\"500 500 0.1\"/>"
                      << "<uavsim_grid type=\"quad\" prefix=\"uav\" rows=\"" << rows << "\" cols=\""
                      << cols << "\" spacing=\"4\" pos=\"0 0 10\"/></worldbody></mujoco>";
  return path;
}

std::unique_ptr<physics::World> load(int n) {
  physics::ComposeOptions o;
  o.models_dir = UAVSIM_MODELS_DIR;
  return physics::World::load(grid_world(n), o);
}

void BM_BareMjStep(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  auto world = load(n);
  // hold every quad where it starts, 10 m up, with a constant force m*g
  for (size_t i = 0; i < world->vehicles().size(); ++i) {
    airframe::Wrench w;
    w.force_enu_n.z() = world->vehicles()[i].airframe.mass_kg * 9.81;
    world->apply_wrench(i, w);
  }
  for (int i = 0; i < 100; ++i) world->step();
  for (auto _ : state) world->step();
  state.SetItemsProcessed(state.iterations() * n);
  state.counters["realtime_x"] =
      benchmark::Counter(static_cast<double>(state.iterations()) * world->timestep_s(), benchmark::Counter::kIsRate);
}

// One warmed-up simulation per N, shared by BM_SimStep and BM_MjStepSameState so that both step the
// same world in the same state (hovering quads, and any that did not make it through the warm-up).
sim::Simulation& warmed(int n, size_t* flying_out) {
  static std::map<int, std::pair<std::unique_ptr<sim::Simulation>, size_t>> cache;
  auto it = cache.find(n);
  if (it != cache.end()) {
    *flying_out = it->second.second;
    return *it->second.first;
  }
  auto owned = std::make_unique<sim::Simulation>(load(n), sim::SimConfig{});
  sim::Simulation& s = *owned;
  // warm-up: the flight controllers boot without gravity (they believe they stand on the ground: the
  // accelerometer reads 1 g, nothing moves); then GUIDED, arm and take off to 5 m while gravity is ramped
  // in over 1 s, so that the climb takes the weight before any controller could judge itself landed
  // (low thrust, no motion); 10 s later the quads hover
  mjModel* m = s.world().mutable_model();
  const double gravity_z = m->opt.gravity[2];
  m->opt.gravity[2] = 0.0;
  auto all_ready = [&s] {
    for (size_t i = 0; i < s.vehicle_count(); ++i) {
      if (!s.fc(i).prearm_ok()) return false;
    }
    return true;
  };
  while (s.time_s() < 20.0 && !all_ready()) s.step();
  for (size_t i = 0; i < s.vehicle_count(); ++i) {
    s.post(i, [](fc::FlightController& f) {
      f.set_mode(fc::Mode::kGuided);
      f.arm(true);
      f.takeoff(5.0);
    });
  }
  const double ramp_start = s.time_s();
  constexpr double kRampS = 1.0;
  while (s.time_s() < ramp_start + kRampS) {
    m->opt.gravity[2] = gravity_z * (s.time_s() - ramp_start) / kRampS;
    s.step();
  }
  m->opt.gravity[2] = gravity_z;
  s.run_until(s.time_s() + 10.0);
  size_t flying = 0;
  for (size_t i = 0; i < s.vehicle_count(); ++i) flying += s.fc(i).armed() && !s.runtime(i).crashed;
  *flying_out = flying;
  return *cache.emplace(n, std::make_pair(std::move(owned), flying)).first->second.first;
}

void BM_SimStep(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  size_t flying = 0;
  sim::Simulation& s = warmed(n, &flying);
  state.counters["flying"] = static_cast<double>(flying);
  for (auto _ : state) s.step();
  state.SetItemsProcessed(state.iterations() * n);
  state.counters["realtime_x"] =
      benchmark::Counter(static_cast<double>(state.iterations()) * s.physics_dt_s(), benchmark::Counter::kIsRate);
}

// Bare mj_step on the warmed-up simulation's own world: the rotor wrenches of its last step stay in
// qfrc_applied; the state is saved and restored every kBatch steps (MuJoCo 2.2 has no mj_getState: time,
// qpos, qvel, act) so the quads do not drift away from the hover being measured.
void BM_MjStepSameState(benchmark::State& state) {
  constexpr int kBatch = 200;
  const int n = static_cast<int>(state.range(0));
  size_t flying = 0;
  physics::World& world = warmed(n, &flying).world();
  const mjModel* m = world.model();
  mjData* d = world.data();
  const double time0 = d->time;
  const std::vector<mjtNum> qpos0(d->qpos, d->qpos + m->nq), qvel0(d->qvel, d->qvel + m->nv),
      act0(d->act, d->act + m->na);
  int k = 0;
  for (auto _ : state) {
    world.step();
    if (++k == kBatch) {
      state.PauseTiming();
      k = 0;
      d->time = time0;
      std::copy(qpos0.begin(), qpos0.end(), d->qpos);
      std::copy(qvel0.begin(), qvel0.end(), d->qvel);
      std::copy(act0.begin(), act0.end(), d->act);
      mj_forward(m, d);
      state.ResumeTiming();
    }
  }
  state.counters["flying"] = static_cast<double>(flying);
  state.SetItemsProcessed(state.iterations() * n);
}

BENCHMARK(BM_BareMjStep)->Arg(1)->Arg(10)->Arg(100)->Arg(1000)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_SimStep)->Arg(1)->Arg(10)->Arg(100)->Arg(1000)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_MjStepSameState)->Arg(1)->Arg(10)->Arg(100)->Arg(1000)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
