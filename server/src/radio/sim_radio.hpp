// The radio in the simulation: a RadioChannel (radio_channel.hpp: the simple model or ns-3) stepped
// in sim time with every vehicle's ground-truth position (the radio is physics, so truth is what it
// should see). The simulation owns it; schedule() registers it to be advanced in every step's
// pre-physics phase and reset with the world (seeded from the sim seed). Obstacles: the paths
// frames use are cast through the world (physics/line_of_sight.hpp), each blocked one adding the
// config's obstacle_loss_db of the geom groups it crosses; cached per link (link_sight_cache.hpp),
// cast again only when a frame uses the link and one of its ends has moved, or the cast is old
// (obstacles move too: a truck, a wall).
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "radio/link_sight_cache.hpp"
#include "radio/ns3_channel.hpp"
#include "radio/radio_channel.hpp"
#include "radio/radio_model.hpp"
#include "sim/simulation.hpp"

namespace uavsim::server::radio {

enum class Backend { kSimple, kNs3 };
const char* backend_name(Backend b);
std::optional<Backend> backend_from_name(const std::string& name);

// Which channel a run uses (--radio-backend, else the world's <text name="uavsim:radio_backend"
// data="simple|ns3"/>, else simple).
struct BackendOptions {
  Backend backend = Backend::kSimple;
  Ns3Options ns3;  // helper_path empty: find_ns3_helper()
};

// The world's <text name="KEY" data="simple|ns3"/>, if it has one; physics::WorldError naming the
// key for any other value. The A2A radio's uavsim:radio_backend and the GCS link's
// uavsim:gcs_link_backend.
std::optional<Backend> world_backend(const physics::World& world, const std::string& key);

// The world's radio settings: uavsim:radio_backend (above) into *backend unless given (nullopt
// keeps it), and <numeric name="uavsim:radio_obstacle_loss_db" data="G0 ... G5"/> (dB per MuJoCo
// geom group, 0 to 1000, up to six values) into config->obstacle_loss_db. Throws
// physics::WorldError naming the attribute when one is malformed or out of range.
void apply_world_radio_settings(const physics::World& world, BackendOptions* backend,
                                bool backend_given, RadioConfig* config);

class SimRadio {
 public:
  // Creates the radio for every vehicle of sim, owned by sim, not yet in its step schedule. Throws
  // std::invalid_argument for an unusable config and std::runtime_error when the ns3 backend's
  // helper cannot be started. Before the loop starts.
  static SimRadio& create(sim::Simulation& sim, const RadioConfig& config,
                          const BackendOptions& backend = {});
  // create(), then schedule(sim.schedule()). Before the loop starts.
  static SimRadio& attach(sim::Simulation& sim, const RadioConfig& config,
                          const BackendOptions& backend = {});
  // Registers the radio as "radio": advance() in the pre-physics phase, reset() as a reset hook.
  // Before the loop starts.
  void schedule(sim::StepSchedule& steps);

  // Queues a frame from vehicle from to to (a vehicle or kBroadcast) at the current sim time. Loop
  // thread only.
  SendResult send(size_t from, int to, const std::vector<uint8_t>& data);
  // Steps the channel to the current sim time; frames arriving by now move to the inbox. Idempotent
  // at a given sim time (the API's gate calls it before announcing a tick, the pre-physics phase
  // calls it again). The gate passes starting_now = false: frames queued at this time (by any
  // lockstep client, in whatever order their requests come) go on air together in pre-physics, so
  // the loss and shadowing draws do not depend on the clients' timing. Loop thread only.
  void advance(bool starting_now = true);
  // The frames that arrived since the last call, in arrival order. Loop thread only.
  std::vector<Delivery> take_deliveries();
  // Frames dropped because nobody took them from a full inbox. Loop thread only.
  uint64_t inbox_overflows() const { return inbox_overflows_; }
  // Frames of vehicle that send() refused because max_queue_frames of its frames were still
  // waiting to go on air (queue_full: it offered more than its airtime carries). Loop thread only.
  uint64_t refused(size_t vehicle) const {
    return vehicle < refused_.size() ? refused_[vehicle] : 0;
  }

  RadioChannel& model() { return *channel_; }  // Loop thread only.
  const RadioChannel& model() const { return *channel_; }

  // Called once, on the loop thread, when the channel fails (the ns3 helper died or hung), with
  // why: the server ends the run. Before the loop starts.
  void set_on_failure(std::function<void(const std::string&)> fn) { on_failure_ = std::move(fn); }

  // Back to the initial state for a reset with seed. Loop thread only.
  void reset(uint64_t seed);

  // The radio's generator seed for a sim seed (its own stream, not the sensors').
  static uint64_t radio_seed(uint64_t sim_seed) {
    return sim_seed * 0x9E3779B97F4A7C15ull + 0x7261646FULL;
  }

  static constexpr size_t kMaxInbox = 1u << 16;

  SimRadio(sim::Simulation& sim, std::unique_ptr<RadioChannel> channel);  // use attach()

 private:
  // the obstacle loss of link (from, to) at the positions of this step, cached
  double link_loss_db(size_t from, size_t to);
  void check_failure();

  sim::Simulation& sim_;
  std::unique_ptr<RadioChannel> channel_;
  LinkSightCache sights_;
  std::vector<Eigen::Vector3d> positions_enu_m_;
  std::vector<Eigen::Vector3d> velocities_enu_m_s_;
  std::vector<Delivery> inbox_;
  uint64_t inbox_overflows_ = 0;
  std::vector<uint64_t> refused_;  // per sender: queue_full refusals
  std::function<void(const std::string&)> on_failure_;
  bool failure_reported_ = false;
};

// A channel of the chosen backend for `nodes` radios (the ns3 helper found by find_ns3_helper()
// unless its path is given). Throws as SimRadio::create.
std::unique_ptr<RadioChannel> make_channel(const BackendOptions& backend, size_t nodes,
                                           const RadioConfig& config, uint64_t seed, double step_s);

}  // namespace uavsim::server::radio
