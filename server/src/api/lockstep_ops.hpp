// The lockstep contract on the sim socket API (docs/protocol.md "Lockstep"): lockstep_join,
// lockstep_leave, done and lockstep_shm, an op group like the others. The contract itself (which
// connections gate the clock, their ticks and deadlines) is the LockstepCoordinator the API
// server's gate consults; these ops change it on a client's request. lockstep_shm moves a
// connection's stream onto shared memory (ShmTransport), for clients on the server's machine only.
//
// Threads: everything runs on the loop thread, inside the gate.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "api/clock_ops.hpp"
#include "api/lockstep_coordinator.hpp"
#include "api/op_table.hpp"
#include "api/shm_transport.hpp"
#include "sim/simulation.hpp"

namespace uavsim::server::api {

class LockstepOps : public OpGroup {
 public:
  // What the ops need of the server around them.
  struct Server {
    Send send;
    // the address conn came from (lockstep_shm serves loopback only)
    std::function<std::string(uint64_t conn)> peer_address;
    // whether any op group prepared output of now for conn before it joined (its first tick is then
    // the next one after now)
    std::function<bool(uint64_t conn)> prepared_before_join;
    // whether a done's mavlink_seq is waited for (the server has a SeqWaiter)
    std::function<bool()> seq_checked;
    // serves a query for conn as if it had sent it now: {"result": ...} or {"error": {code,
    // message}} (lockstep_join's with_tick)
    std::function<Json(uint64_t conn, const Json& request)> serve_query;
  };

  // shm: the shared-memory streams, or null when this server serves none. Everything given must
  // outlive this object.
  LockstepOps(sim::Simulation& sim, LockstepCoordinator& lockstep, ClockOps& clock,
              ShmTransport* shm, Server server);

  // lockstep_join, lockstep_leave, done, lockstep_shm.
  void register_ops(OpTable& table) override;
  // No tick is awaited; every client's next tick starts from sim time 0 (and a client quiet since
  // its done is woken: the reset's messages may matter before that tick).
  void on_reset() override;
  // A connection that closes stops gating the clock.
  void on_disconnect(uint64_t conn) override;
  // Before each tick of a connection that joined with with_tick: its queries answered at the
  // tick's time, as one tick_results event (docs/protocol.md).
  void before_tick(uint64_t conn, const Send& send) override;

 private:
  void op_join(uint64_t conn, const Json& request, OpReply* reply);
  void op_leave(uint64_t conn, const Json& request, OpReply* reply);
  void op_done(uint64_t conn, const Json& request, OpReply* reply);
  void op_shm(uint64_t conn, const Json& request, OpReply* reply);

  sim::Simulation& sim_;
  LockstepCoordinator& lockstep_;
  ClockOps& clock_;
  ShmTransport* shm_;
  Server server_;
  std::map<uint64_t, std::vector<Json>> with_tick_;  // lockstep_join's with_tick, by connection
};

}  // namespace uavsim::server::api
