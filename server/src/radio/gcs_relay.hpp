// The ground-station link impaired in sim time (seed 6.3): a UDP relay per vehicle between a
// vehicle-side port (the UAV's GCS link sends there) and a GCS-side port (the ground station's link
// sends there), that drops datagrams with a seeded loss probability or during an outage window and
// delays the others by a latency, all in sim time. The same client code talks to a real ground
// station without it.
//
// The relay reads its sockets without blocking when pumped (at control steps, on the loop thread):
// a datagram's arrival time is the sim time of the pump that read it, so the relay adds no
// wall-clock behaviour of its own, and it stops with the clock (pause, lockstep). Peers are learned
// from the last datagram each side received; the GCS peer can also be given up front.
//
// Over a radio (--gcs-link-backend ns3, gcs_radio_link.hpp): a datagram due per the impairment
// (the fault API's loss, outage and latency still apply first, on the relay's side) goes on ns-3's
// 802.11 channel instead of straight to its peer, and is sent on at the first pump at or after the
// sim time the channel delivers it; what the channel loses, or refuses (larger than 1500 bytes),
// counts as dropped.
#pragma once

#include <netinet/in.h>

#include <cstdint>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "radio/gcs_radio_link.hpp"
#include "sim/simulation.hpp"

namespace uavsim::server::radio {

struct RelayImpairment {
  double loss_probability = 0.0;  // per datagram, both directions
  double latency_s = 0.0;         // added to every datagram, both directions
  double outage_until_s =
      -std::numeric_limits<double>::infinity();  // everything dropped before this
};

struct RelayStats {
  uint64_t to_gcs_forwarded = 0;
  uint64_t to_gcs_dropped = 0;
  uint64_t to_uav_forwarded = 0;
  uint64_t to_uav_dropped = 0;
};

class GcsRelay {
 public:
  // Binds both sockets on bind_address (port 0: ephemeral); gcs_host/gcs_port, if given, is where
  // vehicle datagrams go before the GCS has sent anything. Null (and *error naming the address) if
  // a socket cannot be opened or bound.
  static std::unique_ptr<GcsRelay> open(const std::string& bind_address, uint16_t uav_port,
                                        uint16_t gcs_port,
                                        const std::optional<std::string>& gcs_host,
                                        std::optional<uint16_t> gcs_target_port, uint64_t seed,
                                        std::string* error);
  ~GcsRelay();
  GcsRelay(const GcsRelay&) = delete;
  GcsRelay& operator=(const GcsRelay&) = delete;

  uint16_t uav_port() const { return uav_port_; }
  uint16_t gcs_port() const { return gcs_port_; }

  // Reads what has arrived on both sockets (never blocks), drops or delays it per the impairment at
  // now_s and sends what is due. Single caller (the loop thread).
  void pump(double now_s);
  // Sets loss and latency, and an outage of outage_s starting at now_s (0: none). Single caller.
  void impair(double loss_probability, double latency_s, double outage_s, double now_s);
  // Back to an unimpaired relay with nothing in flight, the generator restarted from seed. Single
  // caller.
  void reset(uint64_t seed);

  const RelayImpairment& impairment() const { return impairment_; }
  const RelayStats& stats() const { return stats_; }

  // Where due datagrams go instead of straight to their peer: a radio that hands them back through
  // deliver() when they arrive. It returns false when it refuses one (counted dropped). Single
  // caller.
  using Carrier = std::function<bool(bool to_gcs, const std::vector<uint8_t>& bytes)>;
  void set_carrier(Carrier carrier) { carrier_ = std::move(carrier); }
  // Sends a datagram the carrier delivered on to its peer now. Single caller.
  void deliver(bool to_gcs, const std::vector<uint8_t>& bytes);
  // Counts datagrams the carrier lost on the way. Single caller.
  void count_carrier_losses(uint64_t to_gcs, uint64_t to_uav) {
    stats_.to_gcs_dropped += to_gcs;
    stats_.to_uav_dropped += to_uav;
  }

 private:
  struct InFlight {
    double due_s = 0.0;
    bool to_gcs = false;
    std::vector<uint8_t> bytes;
  };
  GcsRelay() = default;
  void receive(int fd, bool to_gcs, double now_s);
  // sends to the peer of that direction, counted forwarded or dropped
  void forward(bool to_gcs, const std::vector<uint8_t>& bytes);
  double uniform();

  int uav_fd_ = -1;
  int gcs_fd_ = -1;
  uint16_t uav_port_ = 0;
  uint16_t gcs_port_ = 0;
  std::optional<sockaddr_in> uav_peer_;
  std::optional<sockaddr_in> gcs_peer_;
  RelayImpairment impairment_;
  RelayStats stats_;
  std::vector<InFlight> in_flight_;  // ordered by due time, arrival order among equals
  std::mt19937_64 rng_;
  Carrier carrier_;  // empty: due datagrams go straight to their peer
};

// Every vehicle's relay, owned by the simulation and pumped at control steps (schedule()).
class GcsRelaySet {
 public:
  // Creates an empty set, owned by sim, not yet in its step schedule. Before the loop starts.
  static GcsRelaySet& create(sim::Simulation& sim, std::string bind_address);
  // create(), then schedule(sim.schedule()). Before the loop starts.
  static GcsRelaySet& attach(sim::Simulation& sim, std::string bind_address);
  // Registers the set as "gcs_relays": pump() in the post-control phase, reset() as a reset hook.
  // Before the loop starts.
  void schedule(sim::StepSchedule& steps);

  // Opens vehicle's relay (replacing one already open). Null and *error if the sockets fail. Loop
  // thread only.
  GcsRelay* open(size_t vehicle, uint16_t uav_port, uint16_t gcs_port,
                 const std::optional<std::string>& gcs_host,
                 std::optional<uint16_t> gcs_target_port, std::string* error);
  GcsRelay* relay(size_t vehicle);  // null if none open. Loop thread only.

  // Every open relay's datagrams due by now, sent and received. Loop thread only.
  void pump();
  // Every open relay back to its initial state for a reset with seed. Loop thread only.
  void reset(uint64_t seed);

  // Carries every relay's datagrams over radio from now on (gcs_radio_link.hpp). Before the loop
  // starts, before any relay opens.
  void use_radio(std::unique_ptr<GcsRadioLink> radio);
  GcsRadioLink* radio() { return radio_.get(); }  // null: the closed-form relay. Loop thread only.
  // "ns3" over a radio, else "simple".
  const char* backend_name() const { return radio_ ? "ns3" : "simple"; }
  // Called once, on the loop thread, when the radio fails (its helper died or hung), with why: the
  // server ends the run. Before the loop starts.
  void set_on_failure(std::function<void(const std::string&)> fn) { on_failure_ = std::move(fn); }

  GcsRelaySet(sim::Simulation& sim, std::string bind_address);  // use attach()

 private:
  static uint64_t relay_seed(uint64_t sim_seed, size_t vehicle) {
    return (sim_seed + 0x6763735FULL) * 0xBF58476D1CE4E5B9ull + vehicle;
  }
  sim::Simulation& sim_;
  std::string bind_address_;
  std::vector<std::unique_ptr<GcsRelay>> relays_;  // per vehicle
  std::unique_ptr<GcsRadioLink> radio_;
  std::function<void(const std::string&)> on_failure_;
  bool failure_reported_ = false;
};

}  // namespace uavsim::server::radio
