// The radio's ops on the sim socket API (docs/protocol.md, "Radio"): radio_send, radio_subscribe,
// radio_unsubscribe, radio_stats, radio_config for the A2A radio (seed 6.2), and gcs_link_open,
// gcs_link_impair, gcs_link_stats for the ground-station link relay (seed 6.3). Received frames
// stream to subscribers at the gate, before the tick at whose sim time they arrive: one
// {"event": "radio", ...} line each, or, for a connection that subscribed with "batch": true, one
// {"event": "radio_batch", "frames": [...]} line a gate with all of them (a lockstep connection's:
// one a tick, with everything since its last, just before the tick) (a flock's broadcasts fan
// out to every neighbour: thousands of frames a sim second, where a line each costs the server a
// serialisation and a socket write and the client a parse, per frame).
#pragma once

#include <cstdint>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "api/op_table.hpp"
#include "radio/gcs_relay.hpp"
#include "radio/sim_radio.hpp"
#include "sim/simulation.hpp"

namespace uavsim::server::api {

class RadioOps : public OpGroup {
 public:
  // relays may be null (the gcs_link_* ops then answer not_available). All must outlive the server.
  RadioOps(sim::Simulation& sim, radio::SimRadio& radio, radio::GcsRelaySet* relays);

  // radio_send, radio_subscribe, radio_unsubscribe, radio_stats, radio_config and the gcs_link_* ops.
  void register_ops(OpTable& table) override;
  // Handles one of those ops: true with *result, or false with *code and *message. Loop thread only.
  bool handle(uint64_t conn, const std::string& op, const Json& request, Json* result,
              std::string* code, std::string* message);
  // Frames that arrived by now: radio events at once; a batch subscriber's in one radio_batch, at
  // once, or, for a connection in lockstep, with the frames of the next gates, just before its tick.
  void on_gate(const Send& send, const InLockstep& in_lockstep) override;
  // The radio_batch a lockstep connection's frames wait in goes out before its tick.
  void before_tick(uint64_t conn, const Send& send) override;
  void on_reset() override { held_.clear(); }
  void on_disconnect(uint64_t conn) override;

 private:
  std::optional<size_t> vehicle(const Json& value, std::string* code, std::string* message) const;
  Json config_json() const;
  bool apply_config(const Json& request, std::string* code, std::string* message);

  sim::Simulation& sim_;
  radio::SimRadio& radio_;
  radio::GcsRelaySet* relays_;
  struct Subscription {
    std::set<size_t> vehicles;  // whose received frames this connection gets
    bool batch = false;         // one radio_batch line a gate instead of a radio line a frame
  };
  std::map<uint64_t, Subscription> subscriptions_;  // by connection
  // batch frames not sent yet, by connection: [to, from, seq, broadcast, time, sent_time, data_b64]
  // each; a lockstep connection's wait here for its tick (it cannot act on them before: one line and
  // one wake-up a tick instead of one a gate)
  std::map<uint64_t, Json> held_;
  void send_held(uint64_t conn, const Send& send);
  // adds the deliveries to held_ (batch subscribers) or sends a radio event each
  void queue_deliveries(const std::vector<radio::Delivery>& arrived, const Send& send);
};

}  // namespace uavsim::server::api
