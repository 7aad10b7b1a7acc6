// The simulation loop: one world, one clock, every vehicle's flight controller, motors and battery.
// step() runs one step of the declared schedule (sim/step_schedule.hpp): every control period (an
// integer number of physics steps) the control phases first (camera capture, the API's gate, the queued
// vehicle tasks in vehicle order, each vehicle's flight controller, what reads the result), then the
// physics phases (wind, world objects, rotor forces, mj_step, the non-finite-state rule, contacts), so
// inputs take effect at control-step boundaries in a fixed order, never in arrival order
// (docs/architecture.md, "One clock"); same world, seed and inputs: bit-identical trajectories.
// Parking (physics/world.hpp): a disarmed vehicle with its motors stopped that has stood still on static
// geometry for kParkAfter_s is parked (held exactly, no contact constraints; its flight controller and
// sensors run on, seeing a vehicle at rest), as is every vehicle that starts on the ground; it wakes when
// it arms, when something moving touches it, or when it is moved (a reset, a carried vehicle).
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include "airframe/airframe.hpp"
#include "fc/flight_controller.hpp"
#include "airframe/wind.hpp"
#include "physics/world.hpp"
#include "sim/events.hpp"
#include "sim/field_conditions.hpp"
#include "sim/step_schedule.hpp"

namespace uavsim::server::sim {

struct SimConfig {
  double physics_hz = 1000.0;
  double control_hz = 500.0;  // rounded to an integer divisor of physics_hz (400 Hz does not divide 1 kHz)
  uint64_t seed = 1;
  double crash_speed_m_s = 3.0;  // landing-gear contact faster than this is a hard impact
  double airborne_after_s = 0.1;  // no contact for this long = airborne (contacts flicker at rest)
  // Flight-controller parameters of vehicle i, set in order at start and again after every reset
  // (--defaults files, the world's uavsim:params texts). A vehicle past the end gets none. An unknown
  // name or a value out of range is a startup error (std::invalid_argument naming it).
  std::vector<std::vector<std::pair<std::string, double>>> vehicle_params;
  // Wind, battery sag, sensor models, gimbals, balloons (sim/field_conditions.hpp); default: ideal.
  FieldConditions field;
};

// A vehicle's runtime state on the loop thread.
struct VehicleRuntime {
  fc::FlightController fc;
  airframe::MotorState motors;
  airframe::BatteryState battery;
  std::vector<double> motor_cmd;
  std::vector<double> motor_lag_alpha;  // per rotor, 1 - exp(-dt/tau) for the physics step
  std::vector<double> thrust_n;
  bool crashed = false;
  bool on_ground = true;
  double last_contact_s = 0.0;  // sim time of the last contact with anything
  bool was_armed = false;       // at the start of the control step, for events
  fc::Mode old_mode = fc::Mode::kStabilize;
  // where the vehicle started: a vehicle whose state goes bad is killed and put back here
  Eigen::Vector3d start_position_enu_m = Eigen::Vector3d::Zero();
  Eigen::Quaterniond start_q_enu_body = Eigen::Quaterniond::Identity();
  bool state_fault = false;  // the one state_fault event was raised
  double thrust_scale = 1.0;  // battery sag: fraction of rated thrust at the present terminal voltage
  double rest_s = 0.0;        // how long it has stood still on static geometry, disarmed (parking)
};

// A command or query for one vehicle, run on the loop thread at the next control boundary.
using VehicleTask = std::function<void(fc::FlightController&)>;

class Simulation;

// Something in the world with behaviour of its own (the truck on its track, balloons that pop):
// Simulation::schedule_object registers its three parts in the step schedule (before_step in the
// pre-physics phase, on_contact as a contact handler, reset as a reset hook).
class WorldObject {
 public:
  virtual ~WorldObject() = default;
  // Before each physics step (move kinematic bodies, carry landed vehicles).
  virtual void before_step(Simulation& sim) = 0;
  // A contact of a vehicle; return true if the object handled it (e.g. a blade popped a balloon), so that
  // it is not judged as a crash.
  virtual bool on_contact(Simulation& sim, const physics::VehicleContact& contact) = 0;
  // Back to the initial state after a reset (seeded randomness restarts from seed).
  virtual void reset(uint64_t seed) = 0;
};

class Simulation {
 public:
  // Takes ownership of a loaded world. Throws std::invalid_argument for unusable rates.
  Simulation(std::unique_ptr<physics::World> world, const SimConfig& config);
  ~Simulation();

  // Advances one physics step. Loop thread only.
  void step();
  // Advances whole physics steps until sim time reaches time_s. Loop thread only.
  void run_until(double time_s);
  // Back to time 0 with a new seed: initial world state, fresh flight controllers, motors and batteries,
  // objects reset, event log cleared, queued tasks dropped. Loop thread only.
  void reset(uint64_t seed);

  double time_s() const;            // Loop thread only.
  uint64_t step_count() const { return steps_; }
  double physics_dt_s() const { return physics_dt_s_; }
  double control_dt_s() const { return physics_dt_s_ * control_decimation_; }
  int control_decimation() const { return control_decimation_; }
  const SimConfig& config() const { return config_; }

  size_t vehicle_count() const { return vehicles_.size(); }
  const std::string& vehicle_name(size_t i) const;
  const airframe::AirframeParams& airframe(size_t i) const;
  fc::FlightController& fc(size_t i) { return vehicles_[i].fc; }  // Loop thread only.
  const fc::FlightController& fc(size_t i) const { return vehicles_[i].fc; }
  const VehicleRuntime& runtime(size_t i) const { return vehicles_[i]; }
  fc::TruthState truth(size_t i) const;  // Loop thread only.
  physics::World& world() { return *world_; }
  const physics::World& world() const { return *world_; }

  // Queues a task for vehicle i; it runs on the loop thread before the next control step, after the
  // tasks queued for lower vehicle indices. Thread-safe. Unknown vehicle: returns false.
  bool post(size_t vehicle, VehicleTask task);

  // Faults. Loop thread only.
  void set_motor_failed(size_t vehicle, size_t rotor, bool failed);
  void kill_vehicle(size_t vehicle, const std::string& reason);

  // The step's phases and who is registered in each (sim/step_schedule.hpp). Loop thread only.
  StepSchedule& schedule() { return schedule_; }
  const StepSchedule& schedule() const { return schedule_; }
  // Keeps component alive as long as the simulation (world objects, the radio): a component the
  // schedule calls. Returns it. Before the loop starts.
  template <class T>
  T& own(std::unique_ptr<T> component) {
    T& ref = *component;
    owned_.emplace_back(std::move(component));
    return ref;
  }
  // Registers object's parts in the schedule under name: before_step in the pre-physics phase,
  // on_contact as a contact handler, reset as a reset hook. The object must outlive the stepping (own
  // it). Before the loop starts.
  void schedule_object(const std::string& name, WorldObject& object);
  // Records an event at the current sim time. Loop thread only.
  void record(EventType type, int vehicle, std::string detail);

  // The wind every vehicle flies in (and balloons sway in); set_params/gust change it. Loop thread only.
  airframe::WindField& wind() { return wind_; }
  const airframe::WindField& wind() const { return wind_; }

  // Events recorded so far (crashes, landings, failures, ...). Loop thread only.
  EventLog& events() { return events_; }

  // A hash of the full physical state (time, qpos, qvel) for determinism checks. Loop thread only.
  uint64_t state_hash() const;

 private:
  void init_vehicles();
  void init_wind();
  // the simulation's own registrations in the schedule
  void schedule_own_work();
  // (queued tasks) => commands applied, in vehicle order
  void run_vehicle_tasks();
  // (truth, battery) => motor commands, battery state; arm and mode events
  void flight_control();
  // every shard's rotor forces and mj_step, each shard on its own thread (one batch of the pool)
  void step_physics();
  // (motor commands, truth, wind) => qfrc_applied for vehicles [first, end) of one shard; a wrench
  // that is not sane is not applied and faults the vehicle (the non-finite-state rule: before
  // mj_step, which would reset the whole world on a non-finite value)
  void rotor_forces(size_t first, size_t end);
  void check_contacts();
  // the non-finite-state rule on the state after mj_step
  void fault_bad_states();
  // disarmed, rotors stopped, (almost) still: a candidate for parking
  bool resting(size_t vehicle) const;
  // a vehicle whose rotor force or state is non-finite or runaway: zeroed, put back, killed; true
  // the first time (when its one state_fault event is due)
  bool put_back(size_t vehicle);

  std::unique_ptr<physics::World> world_;
  SimConfig config_;
  double physics_dt_s_ = 0.001;
  int control_decimation_ = 2;
  uint64_t steps_ = 0;
  std::vector<VehicleRuntime> vehicles_;
  std::vector<physics::VehicleContact> contacts_;
  std::vector<char> faulted_;  // per vehicle: this step's rotor wrench was not sane (2: event due)
  std::vector<char> control_events_;  // per vehicle, this control step: 1 armed or disarmed, 2 mode change
  std::vector<char> touching_, touching_moving_;  // check_contacts' per-vehicle flags, kept allocated
  StepSchedule schedule_;
  std::vector<std::shared_ptr<void>> owned_;  // components the schedule calls (own())
  EventLog events_;
  airframe::WindField wind_{airframe::WindParams{}, 0};

  std::mutex tasks_mutex_;
  std::vector<std::vector<VehicleTask>> pending_tasks_;  // per vehicle, guarded by tasks_mutex_
  std::vector<std::vector<VehicleTask>> running_tasks_;  // loop thread's swap buffer
  bool tasks_pending_ = false;                           // guarded by tasks_mutex_
};

}  // namespace uavsim::server::sim
