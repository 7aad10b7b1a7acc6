// The step schedule: phases in their declared order, the control phases at control steps only,
// slots and registration order inside a phase, registrations made during a step, contact handlers,
// reset hooks, and describe(); then the schedule a Simulation declares for its own work.
#include "sim/step_schedule.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "sim_fixture.hpp"

namespace uavsim::server::sim {
namespace {

using Log = std::vector<std::string>;

// registers name in phase, logging its calls
void add_logged(StepSchedule& s, Log& log, Phase phase, const std::string& name,
                Slot slot = Slot::kNormal) {
  s.add(
      phase, name, [&log, name] { log.push_back(name); }, slot);
}

TEST(StepSchedule, PhasesRunInDeclaredOrderWhateverTheRegistrationOrder) {
  StepSchedule s;
  Log log;
  // registered backwards
  add_logged(s, log, Phase::kContacts, "contacts");
  add_logged(s, log, Phase::kPhysics, "mj_step");
  add_logged(s, log, Phase::kPrePhysics, "pre_physics");
  add_logged(s, log, Phase::kPostControl, "post_control");
  add_logged(s, log, Phase::kFlightControl, "flight_control");
  add_logged(s, log, Phase::kQueuedTasks, "queued_tasks");
  add_logged(s, log, Phase::kCapture, "capture");
  s.run_step(true);
  EXPECT_EQ(log, (Log{"capture", "queued_tasks", "flight_control", "post_control", "pre_physics",
                      "mj_step", "contacts"}));
  // a physics-only step skips the four control phases
  log.clear();
  s.run_step(false);
  EXPECT_EQ(log, (Log{"pre_physics", "mj_step", "contacts"}));
}

TEST(StepSchedule, ControlPhasesAreTheFirstFour) {
  for (size_t p = 0; p < kPhaseCount; ++p) {
    EXPECT_EQ(control_phase(static_cast<Phase>(p)), p < 4) << phase_name(static_cast<Phase>(p));
  }
}

TEST(StepSchedule, InsideAPhaseSlotFirstThenRegistrationOrder) {
  StepSchedule s;
  Log log;
  add_logged(s, log, Phase::kPrePhysics, "last_a", Slot::kLast);
  add_logged(s, log, Phase::kPrePhysics, "normal_a");
  add_logged(s, log, Phase::kPrePhysics, "first_a", Slot::kFirst);
  add_logged(s, log, Phase::kPrePhysics, "normal_b");
  add_logged(s, log, Phase::kPrePhysics, "last_b", Slot::kLast);
  add_logged(s, log, Phase::kPrePhysics, "first_b", Slot::kFirst);
  s.run_step(false);
  const Log expected{"first_a", "first_b", "normal_a", "normal_b", "last_a", "last_b"};
  EXPECT_EQ(log, expected);
  EXPECT_EQ(s.names(Phase::kPrePhysics), expected);
}

TEST(StepSchedule, ARegistrationDuringAStepJoinsAtTheNextStep) {
  StepSchedule s;
  Log log;
  bool added = false;
  // registers into a phase still to come this step, and into its own phase
  s.add(Phase::kQueuedTasks, "adder", [&] {
    log.push_back("adder");
    if (added) return;
    added = true;
    add_logged(s, log, Phase::kPrePhysics, "late_pre_physics");
    add_logged(s, log, Phase::kQueuedTasks, "late_queued");
    s.add_contact_handler("late_handler", [](const physics::VehicleContact&) { return true; });
    s.add_reset("late_reset", [&log](uint64_t) { log.push_back("late_reset"); });
  });
  add_logged(s, log, Phase::kPrePhysics, "pre_physics");
  s.run_step(true);
  EXPECT_EQ(log, (Log{"adder", "pre_physics"}));  // not this step, though its phase came later
  // in the lists once the step has ended
  EXPECT_EQ(s.names(Phase::kQueuedTasks), (Log{"adder", "late_queued"}));
  // from the next step on, after what was registered before (registration order)
  log.clear();
  s.run_step(true);
  EXPECT_EQ(log, (Log{"adder", "late_queued", "pre_physics", "late_pre_physics"}));
  EXPECT_EQ(s.contact_handler_names(), Log{"late_handler"});
  log.clear();
  s.reset(1);
  EXPECT_EQ(log, Log{"late_reset"});
}

TEST(StepSchedule, TheFirstContactHandlerThatHandlesAContactEndsTheSearch) {
  StepSchedule s;
  Log log;
  s.add_contact_handler("deck", [&log](const physics::VehicleContact& c) {
    log.push_back("deck");
    return c.landing_gear;
  });
  s.add_contact_handler("balloon", [&log](const physics::VehicleContact&) {
    log.push_back("balloon");
    return true;
  });
  physics::VehicleContact gear;
  gear.landing_gear = true;
  EXPECT_TRUE(s.handle_contact(gear));
  EXPECT_EQ(log, Log{"deck"});
  log.clear();
  physics::VehicleContact blade;
  blade.landing_gear = false;
  EXPECT_TRUE(s.handle_contact(blade));
  EXPECT_EQ(log, (Log{"deck", "balloon"}));
  EXPECT_FALSE(
      StepSchedule().handle_contact(blade));  // nobody handles it: judged by the simulation
}

TEST(StepSchedule, ResetHooksRunInRegistrationOrderWithTheSeed) {
  StepSchedule s;
  std::vector<uint64_t> seeds;
  Log log;
  s.add_reset("a", [&](uint64_t seed) {
    log.push_back("a");
    seeds.push_back(seed);
  });
  s.add_reset("b", [&](uint64_t seed) {
    log.push_back("b");
    seeds.push_back(seed);
  });
  s.reset(42);
  EXPECT_EQ(log, (Log{"a", "b"}));
  EXPECT_EQ(seeds, (std::vector<uint64_t>{42, 42}));
  EXPECT_EQ(s.reset_names(), (Log{"a", "b"}));
}

TEST(StepSchedule, DescribeListsEveryPhaseWithItsNamesInOrder) {
  StepSchedule s;
  s.add(
      Phase::kQueuedTasks, "tasks", [] {}, Slot::kLast);
  s.add(Phase::kQueuedTasks, "api", [] {});
  for (int i = 0; i < 3; ++i) s.add(Phase::kPostControl, "mavlink", [] {});
  s.add(Phase::kPostControl, "reporter", [] {});
  s.add_contact_handler("truck", [](const physics::VehicleContact&) { return false; });
  s.add_reset("truck", [](uint64_t) {});
  EXPECT_EQ(s.describe(),
            "capture (control steps): -\n"
            "queued_tasks (control steps): api, tasks\n"
            "flight_control (control steps): -\n"
            "post_control (control steps): mavlink x3, reporter\n"
            "pre_physics: -\n"
            "mj_step: -\n"
            "contacts: -; contact handlers: truck\n"
            "reset: truck\n");
}

TEST(StepSchedule, ASimulationDeclaresItsOwnWorkAroundTheComponents) {
  auto sim = testing::make_sim("empty.xml");
  StepSchedule& s = sim->schedule();
  s.add(Phase::kQueuedTasks, "api", [] {});
  s.add(Phase::kPrePhysics, "truck", [] {});
  // the API's gate before the vehicles' tasks; a world object after the wind (and before the rotor
  // forces and the rule's check of them, which run with each shard's mj_step); the rule's state check
  // before contacts are judged
  EXPECT_EQ(s.names(Phase::kQueuedTasks), (Log{"api", "sim.vehicle_tasks"}));
  EXPECT_EQ(s.names(Phase::kFlightControl), Log{"sim.flight_control"});
  EXPECT_EQ(s.names(Phase::kPrePhysics), (Log{"sim.wind", "truck"}));
  EXPECT_EQ(s.names(Phase::kPhysics), Log{"sim.mj_step"});
  EXPECT_EQ(s.names(Phase::kContacts), (Log{"sim.nonfinite_rule.state", "sim.contacts"}));
}

TEST(StepSchedule, ASimulationRunsTheControlPhasesEveryDecimationSteps) {
  auto sim = testing::make_sim("empty.xml");
  ASSERT_EQ(sim->control_decimation(), 2);  // 1000 Hz physics / 500 Hz control
  std::vector<uint64_t> control_steps;      // step_count() when the post-control phase ran
  sim->schedule().add(Phase::kPostControl, "probe",
                      [&] { control_steps.push_back(sim->step_count()); });
  for (int k = 0; k < 6; ++k) sim->step();
  // before that step's mj_step: steps 0, 2, 4
  EXPECT_EQ(control_steps, (std::vector<uint64_t>{0, 2, 4}));
}

}  // namespace
}  // namespace uavsim::server::sim
