// The radio's ops on the sim socket API (docs/protocol.md, "Radio"): radio_send, radio_subscribe,
// radio_unsubscribe, radio_stats, radio_config for the A2A radio (seed 6.2), and gcs_link_open,
// gcs_link_impair, gcs_link_stats for the ground-station link relay (seed 6.3). Received frames
// stream to subscribers at the gate, before the tick at whose sim time they arrive: one
// {"event": "radio", ...} line each, or, for a connection that subscribed with "batch": true, one
// {"event": "radio_batch", "frames": [...]} line a gate with all of them (a flock's broadcasts fan
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
  void on_gate(const Send& send) override;
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
};

}  // namespace uavsim::server::api
