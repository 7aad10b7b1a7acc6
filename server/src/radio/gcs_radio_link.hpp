// The ground-station link over a radio (issue 31): with --gcs-link-backend ns3, every datagram the
// GCS link relays (gcs_relay.hpp) crosses ns-3's IEEE 802.11g ad hoc channel between the vehicle's
// node and a static ground node at the ground station's position, instead of arriving whole at the
// next control step. This class owns that channel: an Ns3Channel (ns3_channel.hpp, its own
// uavsim-ns3-radio helper) with one node per vehicle plus the ground node (index vehicles), stepped
// with the vehicles' true positions and the world's obstacles (physics/line_of_sight.hpp: the same
// losses that block the A2A radio) at the relays' pumps, in sim time.
//
// Choices (docs/protocol.md "Ground-station link relay"):
// - A channel of its own, not the A2A radio's: ground stations talk on a channel apart from the
//   vehicles' mesh (another Wi-Fi channel, or another band), so GCS traffic does not contend with
//   A2A frames even when both are 802.11; the vehicles' GCS datagrams do contend with each other.
// - Unicast, vehicle <-> ground node, with 802.11's ACKs and retries.
// - A datagram larger than max_datagram_bytes (1500, an Ethernet MTU) is dropped and counted, not
//   fragmented: the relay carries each UDP datagram as one frame, and the GCS link's datagrams
//   are far smaller.
// - The ground node stands at gcs_position (--gcs-position or the world's uavsim:gcs_position),
//   else above the vehicles' launch point (default_gcs_position): crews set their ground station
//   up where they launch.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "radio/link_sight_cache.hpp"
#include "radio/ns3_channel.hpp"
#include "radio/radio_channel.hpp"
#include "sim/simulation.hpp"

namespace uavsim::server::radio {

// The GCS link's 802.11 radios: 802.11g at 6 Mbit/s, 20 dBm (a Wi-Fi radio's usual power), the
// standard's -82 dBm sensitivity at 6 Mbit/s (IEEE 802.11-2016, table 18-18), log-distance with the
// A2A radio's 2.5 exponent and 4 dB shadowing: 20 + 82 - 40.05 = 61.95 dB of path loss beyond 1 m,
// so about 10^(61.95 / 25) = 301 m of range without obstacles.
RadioConfig gcs_wifi_config();

// Above the vehicles' launch point: the mean of their initial positions, kGcsAntennaHeight_m
// higher.
inline constexpr double kGcsAntennaHeight_m = 1.5;  // a ground station's antenna on a tripod
Eigen::Vector3d default_gcs_position(const sim::Simulation& sim);

// The largest |coordinate| of a GCS position, m (what --gcs-position and uavsim:gcs_position take).
inline constexpr double kMaxGcsCoordinate_m = 100000.0;
// Why p is not a usable GCS position ("" if it is).
std::string validate_gcs_position(const Eigen::Vector3d& p);

struct GcsRadioOptions {
  Ns3Options ns3;                                     // helper_path empty: find_ns3_helper()
  std::optional<Eigen::Vector3d> gcs_position_enu_m;  // unset: default_gcs_position()
  RadioConfig config = gcs_wifi_config();  // obstacle_loss_db: the world's, as for the A2A radio
};

// The world's GCS link settings: <text name="uavsim:gcs_link_backend" data="simple|ns3"/> into
// *use_ns3 unless backend_given, <numeric name="uavsim:gcs_position" data="X Y Z"/> into
// options->gcs_position_enu_m unless it is set, and the A2A radio's obstacle losses
// (uavsim:radio_obstacle_loss_db, sim_radio.hpp) into options->config. Throws physics::WorldError
// naming the attribute when one is malformed or out of range.
void apply_world_gcs_settings(const physics::World& world, bool backend_given, bool* use_ns3,
                              GcsRadioOptions* options);

class GcsRadioLink {
 public:
  // The link on ns-3's 802.11 for every vehicle of sim. Throws std::invalid_argument for an
  // unusable position or config, std::runtime_error when the helper cannot be started. Before
  // the loop starts.
  GcsRadioLink(sim::Simulation& sim, const GcsRadioOptions& options);
  // The link on a given channel of vehicles + 1 nodes (tests).
  GcsRadioLink(sim::Simulation& sim, std::unique_ptr<RadioChannel> channel,
               const Eigen::Vector3d& gcs_position_enu_m);

  // A datagram that arrived at its receiver, at time_s.
  struct Arrival {
    size_t vehicle = 0;   // whose link
    bool to_gcs = false;  // vehicle -> ground station, else back
    double sent_s = 0.0;
    double time_s = 0.0;
    std::vector<uint8_t> bytes;
  };

  // Puts a datagram of vehicle's link on the channel at the current sim time. False if the channel
  // refuses it: larger than max_datagram_bytes(), its queue full, or the channel failed. Loop
  // thread only.
  bool send(size_t vehicle, bool to_gcs, const std::vector<uint8_t>& bytes);
  // Steps the channel to the current sim time; the datagrams arriving by now go to *out in
  // (arrival, receiver, sender, seq) order. Loop thread only.
  void step(std::vector<Arrival>* out);
  // The datagrams of vehicle's link, one direction, that the channel lost (below sensitivity,
  // interference, blocked) since the last call. Loop thread only.
  uint64_t take_losses(size_t vehicle, bool to_gcs);
  // Back to the initial state for a reset with the sim's seed. Loop thread only.
  void reset(uint64_t sim_seed);

  size_t max_datagram_bytes() const { return channel_->max_payload_bytes(); }
  const Eigen::Vector3d& gcs_position_enu_m() const { return gcs_enu_m_; }
  std::string failure() const { return channel_->failure(); }
  RadioChannel& channel() { return *channel_; }  // Loop thread only.

  // The channel's seed for a sim seed: a stream apart from the A2A radio's.
  static uint64_t gcs_radio_seed(uint64_t sim_seed) {
    return (sim_seed ^ 0x6763737769666931ULL) * 0x9E3779B97F4A7C15ull;
  }

 private:
  double link_loss_db(size_t from, size_t to);
  uint64_t channel_losses(size_t vehicle, bool to_gcs) const;

  sim::Simulation& sim_;
  std::unique_ptr<RadioChannel> channel_;
  Eigen::Vector3d gcs_enu_m_;
  size_t ground_;          // the ground node's index: the vehicle count
  LinkSightCache sights_;  // the ground node's index is past the vehicles: no vehicle
  std::vector<Eigen::Vector3d> positions_enu_m_;
  std::vector<Eigen::Vector3d> velocities_enu_m_s_;
  std::vector<uint64_t> reported_losses_;  // vehicle * 2 + to_gcs
};

}  // namespace uavsim::server::radio
