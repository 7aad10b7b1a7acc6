// The lockstep contract of the sim API (docs/protocol.md "Lockstep contract"; seed 5.3/6.5: gzuav's
// Begin-Tick/End-Tick): which connections gate the clock, the tick each one is due next, its
// "done", and the wall-clock deadline after which a client that does not answer is dropped.
//
// A pure core: no sockets, no threads, no waiting. Wall time comes from an injected clock (the
// steady clock in the server, a fake one in tests); the ApiServer sends the ticks and drops, and
// waits on its request queue until deadline_s(). Not thread-safe: the server calls it on the loop
// thread only.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "uavsim/common/api_error.hpp"

namespace uavsim::server::api {

class LockstepCoordinator {
 public:
  // Monotonic wall-clock seconds from an arbitrary origin.
  using WallClock = std::function<double()>;
  // Has the MAVLink endpoint handled the message with this sequence number on the vehicle's link
  // (or a later one)? SeqWaiter::seq_processed.
  using SeqProcessed = std::function<bool(size_t vehicle, uint8_t seq)>;

  // control_dt_s: the control step (periods are whole multiples of it); default_timeout_s: a
  // joining client's timeout when it names none; physics_dt_s: sim times within a quarter of it are
  // the same instant. now_s must outlive the coordinator.
  LockstepCoordinator(double control_dt_s, double physics_dt_s, double default_timeout_s,
                      WallClock now_s);

  struct Joined {
    double period_s = 0.0;  // the period asked for, rounded to whole control steps (at least one)
    double first_tick_time_s =
        0;  // the next multiple of the period at or after the sim time of joining
    double timeout_s = 0.0;
  };
  // conn joins (or joins again with a new period) at sim time sim_time_s; no tick is awaited from
  // it until its first tick. period_s in (0, 3600] and timeout_s in (0, 1e6] are checked by the
  // caller.
  Joined join(uint64_t conn, double period_s, std::optional<double> timeout_s, double sim_time_s);

  // conn stops gating the clock (lockstep_leave, a disconnect, a drop). If it was the last client
  // that gated it, returns the latest, over the clients that left since the lockstep last had
  // none, of the tick the clock cannot have passed without that client (its next tick, or the
  // tick it is at; a done already sent counts as that tick completed): the same in every run,
  // whenever and in whichever order their leaving is noticed. nullopt if conn was not joined or
  // others remain.
  std::optional<double> leave(uint64_t conn, double sim_time_s);

  bool joined(uint64_t conn) const;
  size_t client_count() const { return clients_.size(); }

  // The clients whose tick falls at sim time sim_time_s and is not announced yet, in connection
  // order.
  std::vector<uint64_t> due(double sim_time_s) const;
  // Starts conn's due tick at sim_time_s: from now on the clock is held until its done (or its
  // deadline, timeout_s of wall time from now). Returns the tick number (sim time / period).
  int64_t begin_tick(uint64_t conn, double sim_time_s);

  // Whether conn may send "done" now, for tick (if given; it must be the one awaited): nullopt if so,
  // otherwise the error (not_joined, bad_state, bad_field) with *message. A connection that
  // was dropped (expire) is told so: when, which tick, its timeout, and to join again.
  std::optional<common::ApiError> check_done(uint64_t conn, std::optional<double> tick,
                                             std::string* message) const;
  // Takes conn's "done" (check_done passed) and returns its tick number. busy_until_s: detached
  // timing (no tick until the first at or after it); wait_seq: vehicle -> the last MAVLink sequence
  // number the client sent before done, each of which must be handled before the tick completes.
  int64_t take_done(uint64_t conn, std::optional<double> busy_until_s,
                    std::map<size_t, uint8_t> wait_seq);

  // Completes every tick whose done has come and whose MAVLink messages are handled (seq_processed
  // null: no MAVLink endpoint, nothing to wait for); those clients' next ticks are scheduled.
  void complete(const SeqProcessed& seq_processed);
  // True while some client's announced tick is not complete: the clock is held.
  bool blocked() const;
  // Drops the clients whose tick's deadline has passed (they stop gating the clock) and returns
  // them, each with the pause time leave() gives for it.
  struct Dropped {
    uint64_t conn = 0;
    std::optional<double> last_left_at_s;  // leave()'s answer
  };
  std::vector<Dropped> expire(double sim_time_s);
  // The earliest deadline (wall seconds on the injected clock) among the ticks still awaited;
  // nullopt when none is.
  std::optional<double> deadline_s() const;
  // True when a client has sent done and only its MAVLink messages are awaited (worth polling
  // soon).
  bool waiting_on_seq() const;

  // The simulation was reset to sim time 0: no tick is awaited and every client's next tick is at
  // 0.
  void reset();

 private:
  struct Client {
    double period_s = 0.0;
    double next_due_s = 0.0;  // sim time of the next tick for this client
    bool awaiting = false;    // a tick was announced and is not complete yet
    int64_t tick = 0;
    double tick_time_s = 0.0;
    double deadline_s = 0.0;  // wall clock
    double timeout_s = 0.0;
    bool done_received = false;
    std::map<size_t, uint8_t> wait_seq;  // vehicle -> MAVLink seq the done named
    std::optional<double> busy_until_s;
  };

  double control_dt_s_;
  double eps_s_;  // a quarter physics step: sim times this close are the same instant
  double default_timeout_s_;
  WallClock now_s_;
  std::map<uint64_t, Client> clients_;  // the joined connections
  // leave(): the latest tick of the clients that left while others remained (reset when the last
  // one leaves, and by reset())
  std::optional<double> latest_left_at_s_;
  // the connections expire() dropped, until they join again or leave: what check_done tells them
  struct DropRecord {
    double sim_time_s = 0.0;
    int64_t tick = 0;
    double timeout_s = 0.0;
  };
  static constexpr std::size_t kMaxDropRecords = 1024;  // the oldest go first
  std::map<uint64_t, DropRecord> dropped_;
};

}  // namespace uavsim::server::api
