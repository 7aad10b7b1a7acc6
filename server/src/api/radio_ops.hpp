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
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "api/op_table.hpp"
#include "api/shm_transport.hpp"
#include "radio/gcs_relay.hpp"
#include "radio/sim_radio.hpp"
#include "sim/simulation.hpp"

namespace uavsim::server::api {

// Where gcs_link_open may aim a relay's datagrams (docs/protocol.md): with allow_remote false
// (uavsim-server's default, --allow-remote-gcs turns it off) only at the requesting API client's own
// address, which peer_address gives for a connection (thread-safe; empty if unknown).
struct GcsTargetPolicy {
  bool allow_remote = true;
  std::function<std::string(uint64_t conn)> peer_address;
};

class RadioOps : public OpGroup {
 public:
  // relays may be null (the gcs_link_* ops then answer not_available). All must outlive the server.
  RadioOps(sim::Simulation& sim, radio::SimRadio& radio, radio::GcsRelaySet* relays,
           GcsTargetPolicy policy = {});

  // radio_send, radio_subscribe, radio_unsubscribe, radio_stats, radio_config and the gcs_link_* ops.
  void register_ops(OpTable& table) override;
  // Frames that arrived by now: radio events at once; a batch subscriber's in one radio_batch, at
  // once, or, for a connection in lockstep, with the frames of the next gates, just before its tick.
  void on_gate(const Send& send, const InLockstep& in_lockstep) override;
  // The radio_batch a lockstep connection's frames wait in goes out before its tick.
  void before_tick(uint64_t conn, const Send& send) override;
  void on_reset() override {
    held_.clear();
    held_binary_.clear();
  }
  // A lockstep batch subscriber on a shared-memory stream gets its frames in its tick's binary
  // record (ShmTransport::set_tick_radio) instead of a radio_batch line. Null: never. Before start.
  void set_shm_transport(ShmTransport* shm) { shm_ = shm; }
  void on_disconnect(uint64_t conn) override;

 private:
  // the ops (loop thread): each answers in *reply
  void op_send(uint64_t conn, const Json& request, OpReply* reply);
  void op_subscribe(uint64_t conn, const Json& request, OpReply* reply);
  void op_unsubscribe(uint64_t conn, const Json& request, OpReply* reply);
  void subscription_op(uint64_t conn, const Json& request, bool subscribe, OpReply* reply);
  void op_stats(uint64_t conn, const Json& request, OpReply* reply);
  void op_config(uint64_t conn, const Json& request, OpReply* reply);
  void op_link_open(uint64_t conn, const Json& request, OpReply* reply);
  void op_link_impair(uint64_t conn, const Json& request, OpReply* reply);
  void op_link_stats(uint64_t conn, const Json& request, OpReply* reply);

  Json config_json() const;
  Json relay_json(size_t vehicle, radio::GcsRelay& r) const;
  // the request's vehicle for a gcs_link op (not_available without relays)
  std::optional<size_t> relay_vehicle(const Json& request, OpReply* reply) const;
  // the vehicle's open relay, or null with not_available
  radio::GcsRelay* open_relay(size_t vehicle, OpReply* reply) const;

  sim::Simulation& sim_;
  radio::SimRadio& radio_;
  radio::GcsRelaySet* relays_;
  GcsTargetPolicy policy_;
  struct Subscription {
    std::set<size_t> vehicles;  // whose received frames this connection gets
    bool batch = false;         // one radio_batch line a gate instead of a radio line a frame
  };
  std::map<uint64_t, Subscription> subscriptions_;  // by connection
  // batch frames not sent yet, by connection: [to, from, seq, broadcast, time, sent_time, data_b64]
  // each; a lockstep connection's wait here for its tick (it cannot act on them before: one line and
  // one wake-up a tick instead of one a gate)
  std::map<uint64_t, Json> held_;
  // the same for a lockstep connection on a shared-memory stream, as the frames themselves
  std::map<uint64_t, std::vector<radio::Delivery>> held_binary_;
  ShmTransport* shm_ = nullptr;
  void send_held(uint64_t conn, const Send& send);
  // adds the deliveries to held_ or held_binary_ (batch subscribers) or sends a radio event each;
  // takes the frames' bytes
  void queue_deliveries(std::vector<radio::Delivery>&& arrived, const Send& send,
                        const InLockstep& in_lockstep);
};

}  // namespace uavsim::server::api
