// The event stream on the sim socket API (docs/protocol.md "Events"): events (the backlog),
// subscribe_events and unsubscribe_events, an op group like the others. The simulation's event log
// (crash, touchdown, arm, ...) streams to subscribers as {"event": "sim_event", ...}, and a reset
// as
// {"event": "reset", "seed"}.
//
// Threads: everything runs on the loop thread, inside the gate.
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <set>

#include "api/op_table.hpp"
#include "sim/simulation.hpp"

namespace uavsim::server::api {

class EventOps : public OpGroup {
 public:
  // sim must outlive this object; send streams the events.
  EventOps(sim::Simulation& sim, Send send);

  // events, subscribe_events, unsubscribe_events.
  void register_ops(OpTable& table) override;
  // Starts the stream again at the reset log's first event and tells the subscribers of the reset
  // (with the simulation's new seed).
  void on_reset() override;
  void on_disconnect(uint64_t conn) override { subscribers_.erase(conn); }

  // Sends every subscriber the events logged since the last call. The gate calls it before and
  // after it runs requests, so a subscription's backlog and its stream neither overlap nor skip.
  void forward();

 private:
  Json event_json(const sim::Event& e) const;
  void op_events(uint64_t conn, const Json& request, OpReply* reply);
  void op_subscribe(uint64_t conn, const Json& request, OpReply* reply);
  void op_unsubscribe(uint64_t conn, const Json& request, OpReply* reply);

  sim::Simulation& sim_;
  Send send_;
  std::set<uint64_t> subscribers_;
  uint64_t forwarded_ = 0;  // the seq of the first event not yet forwarded
};

}  // namespace uavsim::server::api
