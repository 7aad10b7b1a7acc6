// The clock on the sim socket API (docs/protocol.md "Control"): status, pause, pause_at, resume,
// step, set_rate and reset, an op group like the others. It owns the one clock-control path: the
// API server's gate asks it whether the clock is held (paused, a pause_at reached) and counts a
// step's control steps down through it; a step's reply waits until its steps have run, and the
// replies its connection asked for after it wait behind it (hold_reply), so replies keep request
// order.
//
// Threads: everything runs on the loop thread, inside the gate.
#pragma once

#include <cstdint>
#include <functional>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <utility>
#include <vector>

#include "api/lockstep_coordinator.hpp"
#include "api/op_table.hpp"
#include "sim/runner.hpp"
#include "sim/simulation.hpp"

namespace uavsim::server::api {

// The sim API's protocol version (the hello's and status's "protocol").
inline constexpr int kProtocolVersion = 1;

class ClockOps : public OpGroup {
 public:
  // Runs every op group's on_reset (this one's included) after the simulation was reset.
  using ResetGroups = std::function<void()>;

  // runner may be null (set_rate then answers not_available); lockstep is read for status. send
  // answers a step once its steps have run. Everything given must outlive this object.
  ClockOps(sim::Simulation& sim, sim::Runner* runner, const LockstepCoordinator& lockstep,
           bool start_paused, Send send, ResetGroups reset_groups);

  // status, pause, pause_at, resume, step, set_rate, reset.
  void register_ops(OpTable& table) override;
  // Forgets the pauses armed with pause_at.
  void on_reset() override;
  // A step in progress of conn ends unanswered, with the replies held behind it.
  void on_disconnect(uint64_t conn) override;

  // Whether the clock is held (pause, step, a pause_at reached, or start paused).
  bool paused() const { return paused_; }
  // Pauses if a pause armed with pause_at is due: from the first step at or after its time.
  void arm_due_pauses();
  // While paused: true when a requested step is to run now; once the steps are done, sends the
  // step's reply (then the replies held behind it) and returns false.
  bool count_down_step();
  // True if message, a reply to conn, must wait behind conn's step in progress (it is held and sent
  // after the step's own reply); false: send it now.
  bool hold_reply(uint64_t conn, const Json& message);
  // Whether conn has a step in progress (its replies must come on TCP until it ends).
  bool step_in_progress(uint64_t conn) const { return step_reply_ && step_reply_->first == conn; }
  // A lockstep client stopped gating the clock (leave, drop, disconnect); last_at_s: where the
  // coordinator says the clock stands without it, if it was the last (arms the lockstep_empty
  // pause).
  void lockstep_left(std::optional<double> last_at_s);

 private:
  void op_status(uint64_t conn, const Json& request, OpReply* reply);
  void op_pause(uint64_t conn, const Json& request, OpReply* reply);
  void op_pause_at(uint64_t conn, const Json& request, OpReply* reply);
  void op_resume(uint64_t conn, const Json& request, OpReply* reply);
  void op_step(uint64_t conn, const Json& request, OpReply* reply);
  void op_set_rate(uint64_t conn, const Json& request, OpReply* reply);
  void op_reset(uint64_t conn, const Json& request, OpReply* reply);
  // Answers the step in progress (ok at its end, or an `interrupted` error naming by_op when
  // another clock op ended it early) and then the replies held behind it.
  void finish_step(const char* by_op = nullptr);

  sim::Simulation& sim_;
  sim::Runner* runner_;
  const LockstepCoordinator& lockstep_;
  Send send_;
  ResetGroups reset_groups_;
  // the gate holds the clock while paused_
  bool paused_ = false;
  std::set<double> pause_at_s_;  // pause_at: hold the clock once sim time reaches each
  bool pause_when_lockstep_empty_ =
      false;  // pause_at: hold it when the last lockstep client leaves
  uint64_t steps_remaining_ = 0;
  // conn, request id: answered when the steps are done
  std::optional<std::pair<uint64_t, Json>> step_reply_;
  uint64_t steps_requested_ = 0;           // by the step in progress
  std::vector<Json> replies_behind_step_;  // to step_reply_'s connection, answered after its step
};

}  // namespace uavsim::server::api
