// The ns3 backend of the A2A radio: IEEE 802.15.4 as ns-3's lr-wpan models it (O-QPSK 250 kbit/s,
// unslotted CSMA-CA, ACK and retries for unicast, SINR-driven errors, so contention, hidden
// terminals and capture are real), run in the separate program uavsim-ns3-radio (GPL-2.0-only,
// ns3/README.md: ns-3 never links into this Apache-2.0 server). This class spawns the helper, owns
// it, and steps it in lockstep with the physics over a socket pair (ns3/wire.hpp): at a step with
// something to do it pushes every vehicle's position and velocity, the obstacle losses of the links
// the step's senders use and the frames sent, and the helper runs ns-3 to the step's time
// (Simulator::Stop(t - Now()) + Run()) and answers with the receptions and counters. While no frame
// is in flight no round trip is made.
//
// Pipelined (set_pipelined, what SimRadio does): the helper works beside the server instead of
// before it. A step's inputs (positions, losses, frames) go at the step's last call with the time
// of the next step, and the helper runs ns-3 on to that time while the server computes its physics
// step; the answer is read at the next step. That run is the one the next step would have started
// with, so the deliveries, counters and their times are the same as stepped one at a time (test
// Ns3Pipelined.*); the calls must come on the step grid (one starting_now call last at each time,
// the next at now + step_s), else the helper takes inputs at its own time.
//
// Failure: a helper that dies, hangs (no answer within the timeout, wall time) or answers nonsense
// puts the channel in a failed state with a message (failure()); from then on it refuses frames
// and delivers nothing, and SimRadio ends the run (never a silently perfect radio).
//
// Model: the channel's loss is log-distance (reference_loss_db, path_loss_exponent) with gaussian
// shadowing per (transmission, receiver), or the range model; tx_power_dbm and sensitivity_dbm
// are applied by the helper (a signal below sensitivity neither decodes nor interferes). loss,
// collisions (always modelled) and mac_header_bytes (always 11) are not settings here.
// TDMA (tdma, slot_s, period_s, as on the simple backend): the server gives each frame the slot
// the simple model would (tdma_slot_start_s) and hands it over at the last step before that slot;
// the helper puts it to the sender's MAC at the slot's start, with CSMA-CA's random backoff off
// (macMinBE 0) so it goes on air one clear-channel assessment and one turnaround later (320 us).
// Deliveries arrive at max(end of reception + latency_s, queued + one step), like the simple model.
// Without TDMA a frame enters the channel at a seeded offset after it was sent (send_spread_s,
// radio_channel.hpp; at least one step on 802.11): drawn from (seed, sender, send time), so the
// same for every frame a sender sends at one time and independent of the order of the requests.
#pragma once

#include <sys/types.h>

#include <cstdint>
#include <deque>
#include <optional>
#include <string>
#include <vector>

#include "radio/radio_channel.hpp"

namespace uavsim::server::radio {

struct Ns3Options {
  std::string helper_path;        // the uavsim-ns3-radio program
  double reply_timeout_s = 10.0;  // wall seconds the helper may take for one step
};

// Where the helper is: $UAVSIM_NS3_RADIO if set, else beside this program's executable, else the
// build tree's copy (compiled in); nullopt if none exists.
std::optional<std::string> find_ns3_helper();

class Ns3Channel : public RadioChannel {
 public:
  // Spawns the helper and sets it up for vehicles radios. Throws std::runtime_error when the helper
  // cannot be started or does not answer, std::invalid_argument for an unusable config (startup
  // errors).
  Ns3Channel(size_t vehicles, const RadioConfig& config, uint64_t seed, double step_s,
             const Ns3Options& options);
  ~Ns3Channel() override;  // asks the helper to quit, then reaps it
  Ns3Channel(const Ns3Channel&) = delete;
  Ns3Channel& operator=(const Ns3Channel&) = delete;

  const char* backend_name() const override { return "ns3"; }
  size_t max_payload_bytes() const override { return max_payload_bytes_; }
  SendResult send(size_t from, int to, const std::vector<uint8_t>& data, double now_s) override;
  void step(double now_s, const std::vector<Eigen::Vector3d>& positions_enu_m,
            std::vector<Delivery>* out, bool starting_now = true) override;
  bool has_due(double now_s) const override;
  void set_velocities(const std::vector<Eigen::Vector3d>& velocities_enu_m_s) override;
  bool set_config(const RadioConfig& config, std::string* error) override;
  const RadioConfig& config() const override { return config_; }
  void reset(uint64_t seed) override;
  size_t vehicle_count() const override { return vehicles_; }
  const LinkStats& link(size_t from, size_t to) const override {
    return links_[from * vehicles_ + to];
  }
  uint64_t transmitted(size_t vehicle) const override { return transmitted_[vehicle]; }
  size_t queued(size_t vehicle) const override { return queued_[vehicle] + in_flight_[vehicle]; }
  uint64_t channel_access_failures(size_t vehicle) const override {
    return access_failures_[vehicle];
  }

  // Steps the helper one step ahead of the calls (above) when on; off: each step waits for the
  // helper's answer (the default).
  void set_pipelined(bool on) override;

  // Why the helper is unusable ("" while it works).
  std::string failure() const override { return failure_; }
  // The helper's process id (tests end it to check the failure path).
  pid_t helper_pid() const { return pid_; }

  // Why config is unusable on this backend for vehicles vehicles ("" if usable).
  static std::string validate_ns3(const RadioConfig& config, size_t vehicles);
  // The shortest TDMA slot on this backend: a 127-byte PSDU's airtime plus the clear-channel
  // assessment and turnaround the MAC takes before it (4.576 ms).
  static double min_tdma_slot_s();

 private:
  struct Queued {
    size_t from = 0;
    int to = kBroadcast;
    uint64_t seq = 0;
    int64_t queued_ns = 0;
    int64_t slot_ns =
        -1;  // when it enters: its TDMA slot's start, or its spread entry; -1: at once
    std::vector<uint8_t> data;
  };

  void spawn();
  void reset_state();
  // hung: the helper is alive but silent (ended at once, not waited for)
  void fail(const std::string& why, bool hung = false);
  // one request and its reply; false (and failed) on any I/O or protocol error
  bool exchange(const std::vector<uint8_t>& request, std::vector<uint8_t>* reply);
  bool send_request(const std::vector<uint8_t>& request);
  bool read_reply(std::vector<uint8_t>* reply);
  // the queued frames due at now_ns, out of the queue, in the order ns-3 gets them
  std::vector<Queued> take_due(int64_t now_ns, bool starting_now);
  // a slice at t_ns (wire.hpp) with the positions and the frames handed, onto slices_
  void add_slice(int64_t t_ns, const std::vector<Eigen::Vector3d>& positions_enu_m,
                 const std::vector<Queued>& hand);
  // slices_ as one kStep that runs on to ahead_ns (-1: no further); wait: read its answer now
  void send_step(int64_t ahead_ns, bool wait);
  // reads the answer of the kStep sent, if one is out
  void collect();
  bool expect_ready(const std::vector<uint8_t>& request);
  bool read_step_done(const std::vector<uint8_t>& reply);
  int64_t to_ns(double t_s) const;
  // when a frame from sender, sent at queued_ns, enters the channel (send_spread_s); -1: at once
  int64_t entry_ns(size_t from, int64_t queued_ns);

  size_t vehicles_;
  RadioConfig config_;
  double step_s_;
  Ns3Options options_;
  uint64_t seed_;
  pid_t pid_ = -1;
  int fd_ = -1;
  std::string failure_;
  size_t max_payload_bytes_ = 0;
  int64_t requested_ns_ = 0;    // the time of the last slice
  int64_t clock_ns_ = 0;        // the helper's clock in its last answer (ahead of requested_ns_
                                // after a run ahead)
  bool busy_ = false;           // frames in flight in the helper
  int64_t quiet_until_ns_ = 0;  // busy: the helper has nothing to report before this time
  bool pipelined_ = false;
  bool outstanding_ = false;     // a kStep is out, its answer not yet read
  std::vector<uint8_t> slices_;  // slices not yet sent (pipelined: this time's, sent at its end)
  uint32_t slice_count_ = 0;
  std::vector<Eigen::Vector3d> velocities_enu_m_s_;
  std::vector<Queued> queue_;  // sent, not yet handed to the helper, in (time, from, seq)
  std::vector<uint64_t> next_seq_;
  std::vector<size_t> queued_;          // per sender: in queue_
  std::vector<double> busy_until_s_;    // per sender, TDMA: end of its last frame's slot use
  std::vector<int64_t> last_entry_ns_;  // per sender: its last frame's entry (frames keep order)
  std::vector<size_t> in_flight_;       // per sender: handed, not yet confirmed
  std::vector<double> pushed_loss_db_;  // from * N + to: the obstacle loss the helper has
  std::vector<Delivery> pending_;       // received, not yet arrived (latency, one-step floor)
  std::vector<LinkStats> links_;
  std::vector<uint64_t> transmitted_;
  std::vector<uint64_t> access_failures_;
};

}  // namespace uavsim::server::radio
