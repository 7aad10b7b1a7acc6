// The server's own op groups (clock_ops.hpp, event_ops.hpp, lockstep_ops.hpp) called as the API
// server calls them, without a socket: every op declared with its fields, a mistyped field refused
// before the handler runs, a step's reply and the replies behind it, the event stream and
// lockstep's policies.
#include <gtest/gtest.h>

#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "api/clock_ops.hpp"
#include "api/event_ops.hpp"
#include "api/lockstep_ops.hpp"
#include "call_op.hpp"
#include "physics/world.hpp"

namespace uavsim::server::api {
namespace {

using Json = nlohmann::json;
using testing::call_op;

// what a group sent, to which connection
struct Sent {
  uint64_t conn;
  Json message;
};

// One simulation with the three groups wired as ApiServer wires them (no transport: lockstep_shm
// has no shared-memory stream, and every peer is the one peer_ says).
class ServerOps : public ::testing::Test {
 protected:
  ServerOps()
      : sim_(load_world()),
        lockstep_(sim_->control_dt_s(), sim_->physics_dt_s(), 10.0, [] { return 0.0; }),
        clock_(*sim_, nullptr, lockstep_, false, send(), [this] { reset_groups(); }),
        events_(*sim_, send()),
        lockstep_ops_(*sim_, lockstep_, clock_, nullptr, around()) {}

  static std::unique_ptr<sim::Simulation> load_world() {
    physics::ComposeOptions o;
    o.models_dir = UAVSIM_MODELS_DIR;
    return std::make_unique<sim::Simulation>(
        physics::World::load(std::string(UAVSIM_MODELS_DIR) + "/worlds/mbzirc2020.xml", o),
        sim::SimConfig{});
  }
  OpGroup::Send send() {
    return [this](uint64_t conn, const Json& m) { sent_.push_back({conn, m}); };
  }
  LockstepOps::Server around() {
    LockstepOps::Server s;
    s.send = send();
    s.peer_address = [this](uint64_t) { return peer_; };
    s.prepared_before_join = [this](uint64_t) { return prepared_; };
    s.seq_checked = [] { return false; };
    return s;
  }
  void reset_groups() {
    ++resets_;
    clock_.on_reset();
    events_.on_reset();
    lockstep_ops_.on_reset();
  }
  // one control step of the simulation
  void control_step() {
    for (int i = 0; i < sim_->control_decimation(); ++i) sim_->step();
  }

  std::unique_ptr<sim::Simulation> sim_;
  LockstepCoordinator lockstep_;
  std::vector<Sent> sent_;
  std::string peer_ = "127.0.0.1";
  bool prepared_ = false;
  int resets_ = 0;
  ClockOps clock_;
  EventOps events_;
  LockstepOps lockstep_ops_;
};

TEST_F(ServerOps, EveryOpIsRegisteredInItsGroupWithItsFieldsInTheHellosOrder) {
  OpTable table;
  clock_.register_ops(table);
  events_.register_ops(table);
  lockstep_ops_.register_ops(table);
  const std::vector<std::string> expected = {
      "status",        "pause",          "pause_at", "resume",           "step",
      "set_rate",      "reset",          "events",   "subscribe_events", "unsubscribe_events",
      "lockstep_join", "lockstep_leave", "done",     "lockstep_shm"};
  EXPECT_EQ(table.names(), expected);
  for (const std::string& name : expected) {
    const OpSpec* op = table.find(name);
    ASSERT_NE(op, nullptr) << name;
    EXPECT_TRUE(op->handler) << name;
    EXPECT_EQ(op->thread, OpThread::kLoop) << name;
    EXPECT_FALSE(op->typed_fields.empty()) << name;
  }
  EXPECT_EQ(table.find("status")->group, "clock");
  EXPECT_EQ(table.find("events")->group, "events");
  EXPECT_EQ(table.find("done")->group, "lockstep");
}

TEST_F(ServerOps, AMistypedFieldIsRefusedBeforeTheOpActs) {
  EXPECT_EQ(call_op(clock_, "step", {{"steps", "ten"}})["error"], "bad_field");
  EXPECT_EQ(call_op(clock_, "step", {{"steps", 1e12}})["error"], "bad_field");
  EXPECT_EQ(call_op(clock_, "pause", {{"steps", true}})["error"], "bad_field");
  EXPECT_FALSE(clock_.paused());  // neither the step nor the pause held the clock
  EXPECT_EQ(call_op(clock_, "reset", {{"seed", -1}})["error"], "bad_field");
  EXPECT_EQ(resets_, 0);
  EXPECT_EQ(call_op(events_, "subscribe_events", {{"from_seq", "0"}})["error"], "bad_field");
  EXPECT_EQ(call_op(lockstep_ops_, "lockstep_join", {{"period_s", -1.0}})["error"], "bad_field");
  EXPECT_EQ(lockstep_.client_count(), 0u);
}

TEST_F(ServerOps, AStepIsAnsweredWhenItsStepsHaveRunAndHoldsTheRepliesBehindIt) {
  EXPECT_TRUE(call_op(clock_, "step", {{"id", 7}, {"steps", 2}}, 1).empty());  // deferred
  EXPECT_TRUE(clock_.paused());
  EXPECT_TRUE(clock_.step_in_progress(1));
  // a reply to the stepping connection waits; another connection's does not
  EXPECT_TRUE(clock_.hold_reply(1, Json{{"id", 8}}));
  EXPECT_FALSE(clock_.hold_reply(2, Json{{"id", 9}}));
  EXPECT_TRUE(clock_.count_down_step());
  EXPECT_TRUE(clock_.count_down_step());
  EXPECT_TRUE(sent_.empty());
  EXPECT_FALSE(clock_.count_down_step());  // done: the step's reply, then the one held behind it
  ASSERT_EQ(sent_.size(), 2u);
  EXPECT_EQ(sent_[0].conn, 1u);
  EXPECT_EQ(sent_[0].message["id"], 7);
  EXPECT_TRUE(sent_[0].message["ok"]);
  EXPECT_EQ(sent_[1].message["id"], 8);
  EXPECT_FALSE(clock_.step_in_progress(1));
}

TEST_F(ServerOps, APauseInterruptsAStepAndSaysHowFarItGot) {
  (void)call_op(clock_, "step", {{"id", 1}, {"steps", 3}}, 1);
  EXPECT_TRUE(clock_.count_down_step());
  EXPECT_EQ(call_op(clock_, "pause", Json::object(), 2)["paused"], true);
  ASSERT_EQ(sent_.size(), 1u);
  EXPECT_EQ(sent_[0].message["error"]["code"], "interrupted");
  EXPECT_NE(sent_[0].message["error"]["message"].get<std::string>().find("after 1 of 3 steps"),
            std::string::npos);
  EXPECT_FALSE(clock_.count_down_step());  // nothing left to run
}

TEST_F(ServerOps, ADisconnectDropsItsStepUnanswered) {
  (void)call_op(clock_, "step", {{"steps", 1}}, 1);
  clock_.on_disconnect(1);
  EXPECT_FALSE(clock_.step_in_progress(1));
  EXPECT_TRUE(clock_.count_down_step());
  EXPECT_FALSE(clock_.count_down_step());
  EXPECT_TRUE(sent_.empty());
}

TEST_F(ServerOps, PauseAtHoldsTheClockFromItsTimeAndResetForgetsIt) {
  const Json armed = call_op(clock_, "pause_at", {{"time_s", 2 * sim_->control_dt_s()}});
  ASSERT_EQ(armed["pause_at_s"].size(), 1u);
  clock_.arm_due_pauses();
  EXPECT_FALSE(clock_.paused());
  control_step();
  control_step();
  clock_.arm_due_pauses();
  EXPECT_TRUE(clock_.paused());
  // a second one, then a reset: every group hears it, and the armed pause is gone
  (void)call_op(clock_, "pause_at", {{"time_s", 10.0}});
  EXPECT_EQ(call_op(clock_, "reset", {{"seed", 5}})["seed"], 5);
  EXPECT_EQ(resets_, 1);
  EXPECT_EQ(call_op(clock_, "pause_at", {{"lockstep_empty", true}})["pause_at_s"].size(), 0u);
}

TEST_F(ServerOps, PauseAtLockstepEmptyHoldsTheClockWhereTheLastClientLeft) {
  (void)call_op(clock_, "pause_at", {{"lockstep_empty", true}});
  (void)call_op(lockstep_ops_, "lockstep_join", {{"period_s", sim_->control_dt_s()}}, 3);
  EXPECT_EQ(call_op(clock_, "status", Json::object())["lockstep_clients"], 1);
  lockstep_ops_.on_disconnect(3);
  EXPECT_EQ(lockstep_.client_count(), 0u);
  clock_.arm_due_pauses();
  EXPECT_TRUE(clock_.paused());
}

TEST_F(ServerOps, SubscribersGetTheStreamAndTheReset) {
  const Json backlog = call_op(events_, "subscribe_events", {{"from_seq", 0}}, 4);
  EXPECT_EQ(backlog["events"].size(), 0u);
  sim_->events().add(sim_->time_s(), sim::EventType::kCrash, 0, "test");
  events_.forward();
  ASSERT_EQ(sent_.size(), 1u);
  EXPECT_EQ(sent_[0].conn, 4u);
  EXPECT_EQ(sent_[0].message["event"], "sim_event");
  EXPECT_EQ(sent_[0].message["type"], "crash");
  events_.forward();  // nothing new
  EXPECT_EQ(sent_.size(), 1u);
  // the backlog holds what was forwarded
  EXPECT_EQ(call_op(events_, "events", Json::object())["next_seq"], 1);
  (void)call_op(clock_, "reset", {{"seed", 9}});
  ASSERT_EQ(sent_.size(), 2u);
  EXPECT_EQ(sent_[1].message, (Json{{"event", "reset"}, {"seed", 9}}));
  events_.on_disconnect(4);
  sim_->events().add(sim_->time_s(), sim::EventType::kCrash, 0, "again");
  events_.forward();
  EXPECT_EQ(sent_.size(), 2u);
}

TEST_F(ServerOps, AConnectionWithOutputPreparedBeforeJoiningTicksAfterNow) {
  // at t = 0 a tick is due now, unless the connection's frames of now were captured before it
  // joined
  EXPECT_EQ(call_op(lockstep_ops_, "lockstep_join", {{"period_s", 0.1}}, 1)["first_tick_time"],
            0.0);
  prepared_ = true;
  EXPECT_GT(call_op(lockstep_ops_, "lockstep_join", {{"period_s", 0.1}}, 2)["first_tick_time"],
            0.0);
}

TEST_F(ServerOps, DoneSaysWhetherTheMavlinkSequenceIsChecked) {
  (void)call_op(lockstep_ops_, "lockstep_join", {{"period_s", sim_->control_dt_s()}}, 1);
  const int64_t tick = lockstep_.begin_tick(1, sim_->time_s());
  const Json done = call_op(lockstep_ops_, "done", {{"tick", tick}}, 1);
  EXPECT_EQ(done["tick"], tick);
  EXPECT_EQ(done["mavlink_seq_checked"], false);
  EXPECT_EQ(call_op(lockstep_ops_, "done", {{"tick", "one"}}, 1)["error"], "bad_field");
}

TEST_F(ServerOps, TheSharedMemoryStreamIsNotServedWithoutOne) {
  EXPECT_EQ(call_op(lockstep_ops_, "lockstep_shm", Json::object())["error"], "not_available");
}

TEST_F(ServerOps, SetRateWithoutARunnerIsNotAvailableAndOutOfRangeIsRefused) {
  EXPECT_EQ(call_op(clock_, "set_rate", {{"rate", 2.0}})["error"], "not_available");
  EXPECT_EQ(call_op(clock_, "set_rate", {{"rate", 1e-6}})["error"], "bad_field");
  EXPECT_EQ(call_op(clock_, "set_rate", Json::object())["error"], "missing_field");
}

}  // namespace
}  // namespace uavsim::server::api
