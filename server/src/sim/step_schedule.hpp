// One simulation step as a declared schedule: named phases in a fixed order, each a list of named
// callbacks that components register (docs/architecture.md, "The step schedule"). The simulation
// registers its own work (queued vehicle tasks, flight controllers, rotor forces, mj_step, the
// non-finite-state rule, contact judging); the server registers its components (camera capture, the
// sim API's gate, telemetry, world objects, the radio) once, in one block of server_app.cpp.
//
// Order inside a phase: by slot (kFirst, kNormal, kLast), then by registration order. Components
// use kNormal; the simulation places its own work in kFirst or kLast where it must run before or
// after every component of that phase, so the order never depends on when a component was
// registered relative to the simulation.
//
// Registering during a step: a callback added while a step runs (from inside a callback) is held
// back and joins its phase at the start of the next step; it never runs in the step that added it,
// even if its phase is still to come. Contact handlers and reset hooks follow the same rule.
#pragma once

#include <deque>

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "sim/loop_watchdog.hpp"
#include "physics/world.hpp"

namespace uavsim::server::sim {

// The phases of one step, in the order they run. The first four run at control steps only (every
// control_decimation physics steps, before that step's physics); the rest at every physics step.
enum class Phase : uint8_t {
  kCapture,        // camera snapshots due now (the state the previous step left)
  kQueuedTasks,    // the sim API's requests and lockstep gate, then the vehicles' queued tasks
  kFlightControl,  // every vehicle's flight controller; arm and mode events
  kPostControl,    // what reads the control step's result: telemetry, event output, gimbal commands
  kPrePhysics,     // wind, world objects and radio, then rotor forces into qfrc_applied
  kPhysics,        // mj_step
  kContacts,       // the non-finite-state rule, then contacts judged (crash, touchdown, parking)
};
inline constexpr std::size_t kPhaseCount = 7;

// "capture", "queued_tasks", ... (snake case, as describe() prints them).
const char* phase_name(Phase phase);
// True for the phases that run at control steps only.
bool control_phase(Phase phase);

// Where a callback sits inside its phase.
enum class Slot : uint8_t { kFirst, kNormal, kLast };

class StepSchedule {
 public:
  using Callback = std::function<void()>;
  // Returns true when the contact was handled (e.g. a blade popped a balloon): it is then not
  // judged as a crash, and no later handler sees it.
  using ContactHandler = std::function<bool(const physics::VehicleContact& contact)>;
  using ResetHook = std::function<void(uint64_t seed)>;

  // Registers callback in phase under name (for describe() and profiling). Whatever the callback
  // refers to must outlive the stepping. Loop thread only.
  void add(Phase phase, std::string name, Callback callback, Slot slot = Slot::kNormal);
  // Registers a contact handler (consulted in the contacts phase, in registration order). Loop
  // thread only.
  void add_contact_handler(std::string name, ContactHandler handler);
  // Registers a reset hook (run by Simulation::reset after the world is back at time 0, in
  // registration order). Loop thread only.
  void add_reset(std::string name, ResetHook hook);

  // Runs one step: every phase in order, the control phases only when control is true; then adds
  // what was registered during the step. Loop thread only.
  void run_step(bool control);
  // The loop's trail for the watchdog: run_step enters each entry under "phase/name".
  LoopActivity& activity() { return activity_; }
  const LoopActivity& activity() const { return activity_; }
  // The contact handlers in order until one handles contact; true if one did. Loop thread only.
  bool handle_contact(const physics::VehicleContact& contact);
  // Every reset hook in order. Loop thread only.
  void reset(uint64_t seed);

  // The names registered in phase, in the order they run (pending registrations not included).
  std::vector<std::string> names(Phase phase) const;
  std::vector<std::string> contact_handler_names() const;
  std::vector<std::string> reset_names() const;
  // One line per phase: "queued_tasks (control steps): api, sim.vehicle_tasks"; a name registered
  // several times in a row is written once with its count ("mavlink x3").
  std::string describe() const;

 private:
  struct Entry {
    std::string name;
    Callback callback;
    Slot slot = Slot::kNormal;
    const char* trail = nullptr;  // "phase/name", in trail_names_ (stable for the watchdog's reads)
  };
  struct Pending {
    Phase phase = Phase::kCapture;
    Entry entry;
  };
  void insert(Phase phase, Entry entry);
  void add_pending();

  std::array<std::vector<Entry>, kPhaseCount> phases_;
  std::vector<std::pair<std::string, ContactHandler>> contact_handlers_;
  std::vector<std::pair<std::string, ResetHook>> reset_hooks_;
  bool running_ = false;
  LoopActivity activity_;
  std::deque<std::string> trail_names_;  // never shrinks: a deque keeps its elements in place
  std::vector<Pending> pending_;
  std::vector<std::pair<std::string, ContactHandler>> pending_handlers_;
  std::vector<std::pair<std::string, ResetHook>> pending_resets_;
};

}  // namespace uavsim::server::sim
