// The radio in the simulation: a RadioModel stepped in sim time with every vehicle's ground-truth
// position (the radio is physics, so truth is what it should see). The simulation owns it; schedule()
// registers it to be advanced in every step's pre-physics phase and reset with the world (seeded from
// the sim seed).
#pragma once

#include <cstdint>
#include <vector>

#include "radio/radio_model.hpp"
#include "sim/simulation.hpp"

namespace uavsim::server::radio {

class SimRadio {
 public:
  // Creates the radio for every vehicle of sim, owned by sim, not yet in its step schedule. Throws
  // std::invalid_argument for an unusable config. Before the loop starts.
  static SimRadio& create(sim::Simulation& sim, const RadioConfig& config);
  // create(), then schedule(sim.schedule()). Before the loop starts.
  static SimRadio& attach(sim::Simulation& sim, const RadioConfig& config);
  // Registers the radio as "radio": advance() in the pre-physics phase, reset() as a reset hook.
  // Before the loop starts.
  void schedule(sim::StepSchedule& steps);

  // Queues a frame from vehicle from to to (a vehicle or kBroadcast) at the current sim time. Loop
  // thread only.
  SendResult send(size_t from, int to, const std::vector<uint8_t>& data);
  // Steps the model to the current sim time; frames arriving by now move to the inbox. Idempotent
  // at a given sim time (the API's gate calls it before announcing a tick, the pre-physics phase calls
  // it again). The gate passes starting_now = false: frames queued at this time (by any lockstep
  // client, in whatever order their requests come) go on air together in pre-physics, so the
  // loss and shadowing draws do not depend on the clients' timing. Loop thread only.
  void advance(bool starting_now = true);
  // The frames that arrived since the last call, in arrival order. Loop thread only.
  std::vector<Delivery> take_deliveries();
  // Frames dropped because nobody took them from a full inbox. Loop thread only.
  uint64_t inbox_overflows() const { return inbox_overflows_; }

  RadioModel& model() { return model_; }  // Loop thread only.
  const RadioModel& model() const { return model_; }

  // Back to the initial state for a reset with seed. Loop thread only.
  void reset(uint64_t seed);

  // The radio's generator seed for a sim seed (its own stream, not the sensors').
  static uint64_t radio_seed(uint64_t sim_seed) {
    return sim_seed * 0x9E3779B97F4A7C15ull + 0x7261646FULL;
  }

  static constexpr size_t kMaxInbox = 1u << 16;

  SimRadio(sim::Simulation& sim, const RadioConfig& config);  // use attach()

 private:
  sim::Simulation& sim_;
  RadioModel model_;
  std::vector<Eigen::Vector3d> positions_enu_m_;
  std::vector<Delivery> inbox_;
  uint64_t inbox_overflows_ = 0;
};

}  // namespace uavsim::server::radio
