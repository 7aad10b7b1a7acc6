// The A2A radio's channel (seed 6.2): what every backend of the simulated IEEE 802.15.4 radio
// offers the simulation. Two backends implement it:
//   simple  radio_model.hpp: closed form (range or log-distance with shadowing, seeded loss, TDMA,
//           optional collisions), in process
//   ns3     ns3_channel.hpp: ns-3's lr-wpan (CSMA-CA or the same TDMA, ACKs and retries, SINR
//           errors) in the separate GPL-2.0 program uavsim-ns3-radio (ns3/README.md), stepped
//           in lockstep over a socket pair
// Both are stepped in sim time by one caller (the loop thread) with the vehicles' true positions.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace uavsim::server::radio {

inline constexpr size_t kMaxFrameBytes = 127;  // 802.15.4 aMaxPHYPacketSize
// The largest payload of any technology: 802.11 on the ns3 backend carries an Ethernet MTU's 1500
// bytes (its MSDU could take 2304; 1500 is what IP over Wi-Fi uses and what a program can count on)
inline constexpr size_t kLargestFrameBytes = 1500;
inline constexpr double kBitRateBitS = 250000.0;  // 2.4 GHz O-QPSK PHY
inline constexpr size_t kPhyOverheadBytes =
    6;  // preamble (4) + start-of-frame delimiter (1) + length (1)
inline constexpr int kBroadcast = -1;
inline constexpr size_t kGeomGroups = 6;          // MuJoCo's mjNGROUP
inline constexpr size_t kMaxMacHeaderBytes = 25;  // 802.15.4-2006 data frame, two 64-bit addresses

// Time on air of a frame of frame_bytes (PSDU) bytes at 250 kbit/s, PHY header included:
// 127 bytes -> (127 + 6) * 8 / 250000 = 4.256 ms.
double airtime_s(size_t frame_bytes);

enum class Propagation {
  kRange,        // received within range_m
  kLogDistance,  // received when tx_power - PL(d) >= sensitivity, PL(d) = PL(1 m) + 10 n log10(d) +
                 // X_sigma
};
const char* propagation_name(Propagation p);
std::optional<Propagation> propagation_from_name(const std::string& name);

// The radio's technology: the seed's IEEE 802.15.4 (both backends), or IEEE 802.11g ad hoc at a
// fixed 6 Mbit/s (the ns3 backend only: ns-3's wifi module).
enum class Technology { k802154, k80211 };
const char* technology_name(Technology t);  // "802.15.4", "802.11"
std::optional<Technology> technology_from_name(const std::string& name);

struct RadioConfig {
  Technology technology = Technology::k802154;
  Propagation propagation = Propagation::kRange;
  double range_m = 100.0;
  // log-distance path loss with log-normal shadowing (Rappaport, Wireless Communications, eq. 4.69)
  double tx_power_dbm = 0.0;
  double sensitivity_dbm =
      -85.0;  // MRF24J40 datasheet: -95 dBm typical; -85 leaves a fading margin
  double reference_loss_db = 40.05;  // free space at 1 m, 2.4 GHz: 20 log10(4 pi / 0.125 m)
  double path_loss_exponent = 2.5;
  double shadowing_sigma_db = 4.0;  // drawn per (transmission, receiver)
  double loss_probability = 0.0;    // of a frame that reached a receiver in range
  double latency_s = 0.0;  // processing after the end of transmission (delivery is >= one step)
  bool tdma = false;
  double slot_s = 0.01;   // D
  double period_s = 1.0;  // T (the GPS pulse)
  bool collisions =
      false;  // overlapping frames heard at a receiver are both lost (half duplex too)
  size_t max_queue_frames = 256;  // per vehicle; send() refuses more
  // the ns3 backend without TDMA: a frame enters the channel at a seeded offset in [0,
  // send_spread_s) after it was sent, the same for the frames one sender sends at one time (which
  // keep their order). Lockstep programs all send at the server's step boundary, where real ones
  // run on clocks of their own; 802.11's DCF sends at once on an idle medium, so a step's frames
  // would start together and collide: on 802.11 the spread is at least one step. 0 on 802.15.4
  // (its CSMA-CA starts with a random backoff of up to 2.24 ms): frames go to the MAC at once
  double send_spread_s = 0.0;
  // bytes of MAC header and FCS the PHY carries besides a frame's payload: 0 (the default of the
  // simple backend) lets a payload fill the whole 127-byte PSDU; 11 is a data frame with short
  // addresses and a compressed PAN id (frame control 2, sequence 1, PAN 2, two addresses 2 + 2,
  // FCS 2), as the ns3 backend always sends: payloads of at most 127 - 11 = 116 bytes
  size_t mac_header_bytes = 0;
  // loss added to a link whose line of sight crosses a geom of MuJoCo geom group g (0-5), dB; 0:
  // the group does not block (the default: no obstacles). A blocked path takes the largest loss of
  // the groups it crosses (radio/line_of_sight.hpp)
  std::array<double, kGeomGroups> obstacle_loss_db{};
};

enum class Error { kUnknownVehicle, kBadDestination, kEmptyFrame, kFrameTooLarge, kQueueFull };
const char* error_name(Error e);

struct SendResult {
  std::optional<uint64_t> seq;           // the frame's sequence number (per sender), if queued
  Error error = Error::kUnknownVehicle;  // if not
};

struct Delivery {
  size_t to = 0;
  size_t from = 0;
  uint64_t seq = 0;
  bool broadcast = false;
  double queued_s = 0.0;
  double tx_start_s = 0.0;
  double time_s = 0.0;  // arrival at the receiver
  std::vector<uint8_t> data;
};

// Moves the deliveries of pending that arrive at or before now_s (within 1 ns) to the end of *out,
// in (arrival, receiver, sender, seq) order: how every backend hands its arrivals over. The rest
// stay.
void take_arrivals(std::vector<Delivery>* pending, double now_s, std::vector<Delivery>* out);

// One directed link's counters. Every frame addressed to the receiver (unicast to it, or broadcast)
// that went on air counts once in sent and, once resolved, once in exactly one of the others.
struct LinkStats {
  uint64_t sent = 0;
  uint64_t delivered = 0;
  uint64_t lost = 0;          // in range, dropped by the loss draw
  uint64_t collided = 0;      // overlapped another transmission heard at the receiver
  uint64_t out_of_range = 0;  // beyond range (or below sensitivity after shadowing)
  uint64_t no_ack = 0;        // unicast: the sender saw no ACK after its retries (ns3 backend)
};

// The radio channel every backend implements. Loop thread only, every method.
class RadioChannel {
 public:
  virtual ~RadioChannel() = default;

  // "simple" or "ns3".
  virtual const char* backend_name() const = 0;
  // The largest payload send() accepts, bytes: 802.15.4's 127 minus the MAC header the backend
  // accounts for; 1500 on 802.11 (kLargestFrameBytes).
  virtual size_t max_payload_bytes() const = 0;

  // Queues a frame from vehicle from to vehicle to (or kBroadcast) at time now_s.
  virtual SendResult send(size_t from, int to, const std::vector<uint8_t>& data, double now_s) = 0;
  // Advances to now_s (non-decreasing) with every vehicle's position at now_s and appends the
  // frames arriving at or before now_s to *out, ordered by (arrival, receiver, sender, seq). With
  // starting_now false, frames queued at now_s stay off air until a call at now_s with true (the
  // API's gate: lockstep clients may still be sending for this time). Idempotent at a given time
  // but for frames queued since.
  virtual void step(double now_s, const std::vector<Eigen::Vector3d>& positions_enu_m,
                    std::vector<Delivery>* out, bool starting_now = true) = 0;
  // True when step(now_s) needs fresh positions (a frame goes on air, or the channel is busy).
  virtual bool has_due(double now_s) const = 0;
  // The vehicles' velocities at the next step's time (the ns3 backend moves its nodes between
  // steps with them); the simple model does not need them.
  virtual void set_velocities(const std::vector<Eigen::Vector3d>& velocities_enu_m_s) {
    (void)velocities_enu_m_s;
  }

  // The caller's promise that it steps on the grid of step_s (at each time one call with
  // starting_now last, the next at the next step): a backend whose work runs outside this process
  // (ns3) may then run it one step ahead, beside the caller's own work, with the same outcomes.
  virtual void set_pipelined(bool on) { (void)on; }

  // Replaces the config; false (and *error naming the field) if this backend cannot use it.
  virtual bool set_config(const RadioConfig& config, std::string* error) = 0;
  virtual const RadioConfig& config() const = 0;
  // Drops every frame and counter and restarts from seed.
  virtual void reset(uint64_t seed) = 0;

  virtual size_t vehicle_count() const = 0;
  virtual const LinkStats& link(size_t from, size_t to) const = 0;
  virtual uint64_t transmitted(size_t vehicle) const = 0;
  virtual size_t queued(size_t vehicle) const = 0;
  // Frames vehicle gave up because the channel stayed busy (CSMA-CA's CHANNEL_ACCESS_FAILURE; the
  // simple model never defers, so 0 there).
  virtual uint64_t channel_access_failures(size_t vehicle) const {
    (void)vehicle;
    return 0;
  }

  // Why the channel stopped working ("" while it works): the ns3 backend's helper died, hung or
  // answered nonsense. A failed channel delivers nothing; the run must end.
  virtual std::string failure() const { return ""; }

  // The extra loss of the path from vehicle from to vehicle to at the positions of this step, dB
  // (obstacles, radio/line_of_sight.hpp); unset: none. Called only for links a frame uses.
  using LinkLossFn = std::function<double(size_t from, size_t to)>;
  void set_link_loss(LinkLossFn fn) { link_loss_ = std::move(fn); }

 protected:
  double link_loss_db(size_t from, size_t to) const {
    return link_loss_ ? link_loss_(from, to) : 0.0;
  }

 private:
  LinkLossFn link_loss_;
};

}  // namespace uavsim::server::radio
