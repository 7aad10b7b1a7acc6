#include "sim/simulation.hpp"

#include <cmath>
#include <cstring>
#include <stdexcept>

#include "uavsim/common/splitmix.hpp"

namespace uavsim::server::sim {

namespace {

// splitmix64: decorrelates per-vehicle seeds derived from one world seed
uint64_t mix_seed(uint64_t seed, uint64_t index) {
  return common::splitmix64_mix(seed + common::kSplitMixGamma * (index + 1));
}

// Past these a vehicle's rotor wrench or state is a numerical failure (NaN from a controller, a blow-up),
// not flight. Caught here, before MuJoCo: its own check (1e10) resets the whole world to t = 0.
constexpr double kMaxWrench = 1e6;           // N and N m: a copter makes tens
constexpr double kMaxPosition_m = 1e6;
constexpr double kMaxSpeed_m_s = 1e4;
constexpr double kMaxRate_rad_s = 1e4;

// parking: a disarmed vehicle slower than these, its rotors lifting less than kParkLiftRatio of its
// weight, touching static geometry only, for kParkAfter_s (a settled resting contact creeps at
// micrometres per second; a vehicle still sliding or rocking does not park)
constexpr double kParkSpeed_m_s = 0.01;
constexpr double kParkRate_rad_s = 0.02;
constexpr double kParkLiftRatio = 0.01;
constexpr double kParkAfter_s = 0.5;
constexpr double kGravity_m_s2 = 9.81;

// the non-finite-state rule's event details
constexpr const char* kBadControls = "non-finite or runaway rotor force";
constexpr const char* kBadState = "non-finite or runaway state";

// index of the wind's generator stream (vehicles use 0, 1, ...)
constexpr uint64_t kWindStream = 0x57494E44ull;

bool sane(const airframe::Wrench& w) {
  return w.force_enu_n.allFinite() && w.torque_body_nm.allFinite() && w.force_enu_n.norm() <= kMaxWrench &&
         w.torque_body_nm.norm() <= kMaxWrench;
}

bool sane(const fc::TruthState& t) {
  return t.position_enu_m.allFinite() && t.velocity_enu_m_s.allFinite() && t.q_enu_body.coeffs().allFinite() &&
         t.rate_body_rad_s.allFinite() && t.position_enu_m.norm() <= kMaxPosition_m &&
         t.velocity_enu_m_s.norm() <= kMaxSpeed_m_s && t.rate_body_rad_s.norm() <= kMaxRate_rad_s;
}

void fnv1a(uint64_t* h, const void* data, size_t n) {
  const auto* p = static_cast<const unsigned char*>(data);
  for (size_t i = 0; i < n; ++i) {
    *h ^= p[i];
    *h *= 0x100000001B3ull;
  }
}

}  // namespace

Simulation::Simulation(std::unique_ptr<physics::World> world, const SimConfig& config)
    : world_(std::move(world)), config_(config) {
  if (!(config.physics_hz > 0) || !(config.control_hz > 0) || config.control_hz > config.physics_hz) {
    throw std::invalid_argument("physics_hz and control_hz must be positive, control_hz <= physics_hz");
  }
  physics_dt_s_ = 1.0 / config.physics_hz;
  control_decimation_ = std::max(1, static_cast<int>(std::lround(config.physics_hz / config.control_hz)));
  world_->set_timestep_s(physics_dt_s_);
  if (const std::string e = airframe::validate(config.field.wind); !e.empty()) throw std::invalid_argument(e);
  if (config.field.battery_resistance_ohm > 0) {
    for (size_t i = 0; i < world_->vehicles().size(); ++i) {
      world_->mutable_airframe(i).battery.internal_resistance_ohm = config.field.battery_resistance_ohm;
    }
  }

  init_vehicles();
  init_wind();
  pending_tasks_.resize(vehicles_.size());
  running_tasks_.resize(vehicles_.size());
  schedule_own_work();
}

void Simulation::schedule_own_work() {
  // the simulation's own work, placed before (kFirst) or after (kLast) every component of its phase:
  // the API's gate before the vehicles' tasks, world objects and the radio after the wind (and so
  // before the rotor forces, which join each shard's mj_step), the non-finite-state rule before
  // anything judges contacts
  schedule_.add(Phase::kQueuedTasks, "sim.vehicle_tasks", [this] { run_vehicle_tasks(); }, Slot::kLast);
  schedule_.add(Phase::kFlightControl, "sim.flight_control", [this] { flight_control(); }, Slot::kFirst);
  schedule_.add(Phase::kPrePhysics, "sim.wind", [this] {
    if (wind_.active()) wind_.step(physics_dt_s_);
  }, Slot::kFirst);
  schedule_.add(Phase::kPhysics, "sim.mj_step", [this] { step_physics(); }, Slot::kFirst);
  schedule_.add(Phase::kContacts, "sim.nonfinite_rule.state", [this] { fault_bad_states(); }, Slot::kFirst);
  schedule_.add(Phase::kContacts, "sim.contacts", [this] { check_contacts(); }, Slot::kFirst);
}

void Simulation::schedule_object(const std::string& name, WorldObject& object) {
  WorldObject* o = &object;
  schedule_.add(Phase::kPrePhysics, name, [this, o] { o->before_step(*this); });
  schedule_.add_contact_handler(name, [this, o](const physics::VehicleContact& c) { return o->on_contact(*this, c); });
  schedule_.add_reset(name, [o](uint64_t seed) { o->reset(seed); });
}

Simulation::~Simulation() = default;

void Simulation::init_vehicles() {
  vehicles_.clear();
  const auto& bindings = world_->vehicles();
  vehicles_.reserve(bindings.size());
  for (size_t i = 0; i < bindings.size(); ++i) {
    const airframe::AirframeParams& a = bindings[i].airframe;
    VehicleRuntime rt{fc::FlightController(a, mix_seed(config_.seed, i)), airframe::make_motor_state(a),
                      airframe::BatteryState{}, {}, {}, {}, false, true, 0.0};
    rt.battery.voltage_v = a.battery.voltage_full_v;
    rt.motor_cmd.assign(a.rotors.size(), 0.0);
    rt.thrust_n.assign(a.rotors.size(), 0.0);
    rt.motor_lag_alpha = airframe::motor_lag_alpha(a, physics_dt_s_);
    // field sensor models first, so that the vehicle's own parameters override them
    for (const auto& [name, value] : config_.field.sensor_params) {
      if (rt.fc.set_param(name, value) != fc::CommandResult::kAccepted) {
        throw std::invalid_argument("field conditions: parameter " + name + " = " + std::to_string(value) +
                                    ": unknown, or out of its range");
      }
    }
    if (i < config_.vehicle_params.size()) {
      for (const auto& [name, value] : config_.vehicle_params[i]) {
        if (rt.fc.set_param(name, value) != fc::CommandResult::kAccepted) {
          throw std::invalid_argument(bindings[i].name + ": parameter " + name + " = " + std::to_string(value) +
                                      ": unknown, or out of its range");
        }
      }
    }
    const fc::TruthState start = world_->truth(i);
    rt.start_position_enu_m = start.position_enu_m;
    rt.start_q_enu_body = start.q_enu_body;
    vehicles_.push_back(std::move(rt));
  }
}

void Simulation::init_wind() {
  // the configured wind, its direction drawn from the seed where the conditions say so
  airframe::WindParams w = config_.field.wind;
  const uint64_t seed = mix_seed(config_.seed, kWindStream);
  if (config_.field.wind_from_seeded) w.from_deg = 360.0 * static_cast<double>(seed >> 11) * 0x1.0p-53;
  wind_ = airframe::WindField(w, mix_seed(seed, 1));
}

void Simulation::reset(uint64_t seed) {
  config_.seed = seed;
  world_->reset();
  steps_ = 0;
  init_vehicles();
  init_wind();
  {
    std::lock_guard<std::mutex> lock(tasks_mutex_);
    for (auto& q : pending_tasks_) q.clear();
    tasks_pending_ = false;
  }
  events_.clear();
  schedule_.reset(seed);
}

double Simulation::time_s() const { return world_->time_s(); }
const std::string& Simulation::vehicle_name(size_t i) const { return world_->vehicles()[i].name; }
const airframe::AirframeParams& Simulation::airframe(size_t i) const {
  return world_->vehicles()[i].airframe;
}

fc::TruthState Simulation::truth(size_t i) const {
  fc::TruthState t = world_->truth(i);
  t.on_ground = vehicles_[i].on_ground;
  return t;
}

void Simulation::step() {
  schedule_.activity().set_time(time_s());
  schedule_.run_step(steps_ % static_cast<uint64_t>(control_decimation_) == 0);
}

void Simulation::step_physics() {
  // each shard on the thread that steps it: its vehicles' motors, rotor thrusts (at the battery's
  // voltage) and wrenches about the body origin (drag on the velocity relative to the air) into
  // qfrc_applied, the non-finite-state rule on those wrenches, then the shard's mj_step; the rule's
  // events after, in vehicle order, at the time the step started
  const double t0_s = world_->time_s();
  faulted_.assign(vehicles_.size(), 0);
  world_->step([this](size_t first, size_t end) { rotor_forces(first, end); });
  ++steps_;
  for (size_t i = 0; i < vehicles_.size(); ++i) {
    if (faulted_[i] == 2) events_.add(t0_s, EventType::kStateFault, static_cast<int>(i), kBadControls);
  }
}

void Simulation::rotor_forces(size_t first, size_t end) {
  const Eigen::Vector3d& wind_enu_m_s = wind_.velocity_enu_m_s();
  for (size_t i = first; i < end; ++i) {
    VehicleRuntime& v = vehicles_[i];
    const airframe::AirframeParams& a = world_->vehicles()[i].airframe;
    airframe::step_motors_alpha(a, v.motor_cmd.data(), v.motor_lag_alpha.data(), &v.motors);
    airframe::rotor_thrusts(a, v.motors, v.thrust_n.data());
    if (v.thrust_scale != 1.0) {
      for (double& thrust : v.thrust_n) thrust *= v.thrust_scale;
    }
    if (world_->parked(i)) continue;  // held in place: no wrench (zeroed when it parked)
    const fc::TruthState t = world_->truth(i);
    const airframe::Wrench w =
        airframe::compute_wrench(a, v.thrust_n.data(), t.q_enu_body, t.velocity_enu_m_s - wind_enu_m_s);
    if (sane(w)) {
      world_->apply_wrench(i, w);
      continue;
    }
    // never applied: the vehicle is faulted before its shard steps (its event recorded after)
    world_->apply_wrench(i, airframe::Wrench{});
    faulted_[i] = put_back(i) ? 2 : 1;
  }
}

void Simulation::fault_bad_states() {
  for (size_t i = 0; i < vehicles_.size(); ++i) {
    if (!sane(world_->truth(i)) && put_back(i)) record(EventType::kStateFault, static_cast<int>(i), kBadState);
  }
}

bool Simulation::put_back(size_t vehicle) {
  // the style rule for a non-finite vehicle: controls zeroed, the vehicle killed and put back where it
  // started (at rest), one event; the other vehicles fly on. Touches only this vehicle (its shard's
  // thread may run it).
  VehicleRuntime& v = vehicles_[vehicle];
  const airframe::AirframeParams& a = world_->vehicles()[vehicle].airframe;
  std::fill(v.motor_cmd.begin(), v.motor_cmd.end(), 0.0);
  std::fill(v.thrust_n.begin(), v.thrust_n.end(), 0.0);
  v.motors = airframe::make_motor_state(a);
  const double pos[3] = {v.start_position_enu_m.x(), v.start_position_enu_m.y(), v.start_position_enu_m.z()};
  const Eigen::Quaterniond& q = v.start_q_enu_body;
  const double quat[4] = {q.w(), q.x(), q.y(), q.z()};
  world_->set_pose(vehicle, pos, quat);
  if (v.state_fault) return false;
  v.state_fault = true;
  v.crashed = true;  // dead as after a crash, with this one event instead of a crash event
  v.fc.disarm(true);
  return true;
}

void Simulation::run_until(double time_s) {
  // whole steps: stop at the first step boundary at or after time_s
  while (world_->time_s() + 0.5 * physics_dt_s_ < time_s) step();
}

void Simulation::run_vehicle_tasks() {
  // armed state and mode before this step's commands, so command-driven changes become events too
  for (VehicleRuntime& v : vehicles_) {
    v.was_armed = v.fc.armed();
    v.old_mode = v.fc.mode();
  }
  // queued tasks, in vehicle order
  {
    std::lock_guard<std::mutex> lock(tasks_mutex_);
    if (tasks_pending_) {
      std::swap(pending_tasks_, running_tasks_);
      tasks_pending_ = false;
    }
  }
  for (size_t i = 0; i < running_tasks_.size(); ++i) {
    for (VehicleTask& task : running_tasks_[i]) task(vehicles_[i].fc);
    running_tasks_[i].clear();
  }
}

void Simulation::flight_control() {
  const double now = world_->time_s();
  const double dt = control_dt_s();
  // each vehicle's flight controller on the thread that steps its physics shard, noting whether it
  // armed, disarmed or changed mode (while its state is in cache); the events after, in vehicle order
  control_events_.assign(vehicles_.size(), 0);
  world_->for_each_shard_block([&](size_t first, size_t end) {
    for (size_t i = first; i < end; ++i) {
      VehicleRuntime& v = vehicles_[i];
      const airframe::AirframeParams& a = world_->vehicles()[i].airframe;
      v.fc.update(now, truth(i), v.battery, v.motor_cmd.data());
      if (v.crashed) std::fill(v.motor_cmd.begin(), v.motor_cmd.end(), 0.0);
      const bool armed = v.fc.armed();
      if (armed && world_->parked(i)) world_->wake(i);  // before the motors spin up
      airframe::step_battery(a, v.thrust_n.data(), dt, &v.battery);
      v.thrust_scale = airframe::battery_thrust_scale(a, v.battery);
      control_events_[i] = static_cast<char>((armed != v.was_armed ? 1 : 0) | (v.fc.mode() != v.old_mode ? 2 : 0));
    }
  });
  for (size_t i = 0; i < vehicles_.size(); ++i) {
    if (control_events_[i] == 0) continue;
    VehicleRuntime& v = vehicles_[i];
    if (control_events_[i] & 1) record(v.fc.armed() ? EventType::kArmed : EventType::kDisarmed, static_cast<int>(i), "");
    if (control_events_[i] & 2) record(EventType::kModeChange, static_cast<int>(i), fc::mode_name(v.fc.mode()));
  }
}

bool Simulation::resting(size_t i) const {
  const VehicleRuntime& v = vehicles_[i];
  if (v.fc.armed()) return false;
  double lift_n = 0.0;
  for (double thrust : v.thrust_n) lift_n += thrust;
  if (lift_n > kParkLiftRatio * airframe(i).mass_kg * kGravity_m_s2) return false;
  const fc::TruthState t = world_->truth(i);
  return t.velocity_enu_m_s.norm() < kParkSpeed_m_s && t.rate_body_rad_s.norm() < kParkRate_rad_s;
}

void Simulation::check_contacts() {
  std::vector<char>& touching = touching_;
  std::vector<char>& touching_moving = touching_moving_;
  touching.assign(vehicles_.size(), 0);
  touching_moving.assign(vehicles_.size(), 0);
  world_->vehicle_contacts(&contacts_);
  for (const physics::VehicleContact& c : contacts_) {
    VehicleRuntime& v = vehicles_[c.vehicle];
    if (!c.other_static) touching_moving[c.vehicle] = 1;
    if (schedule_.handle_contact(c)) {
      // gear on a deck is still ground contact (the land detector needs it); blades in a balloon are not
      if (c.landing_gear) touching[c.vehicle] = 1;
      continue;
    }
    touching[c.vehicle] = 1;
    if (v.crashed) continue;
    if (c.other_vehicle >= 0) {
      kill_vehicle(c.vehicle, "collision with " + vehicle_name(c.other_vehicle));
    } else if (!c.landing_gear) {
      kill_vehicle(c.vehicle, "hard impact: " + world_->geom_name(c.geom, c.shard) + " hit " +
                                  world_->geom_name(c.other_geom, c.shard));
    } else {
      const double speed = world_->truth(c.vehicle).velocity_enu_m_s.norm();
      if (speed > config_.crash_speed_m_s) {
        kill_vehicle(c.vehicle, "hard landing at " + std::to_string(speed) + " m/s");
      }
    }
  }
  // on the ground: a contact now or within airborne_after_s (a resting contact comes and goes)
  const double now_s = world_->time_s();
  for (size_t i = 0; i < vehicles_.size(); ++i) {
    VehicleRuntime& v = vehicles_[i];
    // parked: on the ground; standing still on static geometry long enough: parks
    if (world_->parked(i)) {
      touching[i] = 1;
    } else if (touching[i] && !touching_moving[i] && resting(i)) {
      v.rest_s += physics_dt_s_;
      if (v.rest_s >= kParkAfter_s) world_->park(i);
    } else {
      v.rest_s = 0.0;
    }
    if (world_->parked(i)) v.rest_s = 0.0;
    if (touching[i]) v.last_contact_s = now_s;
    const bool grounded = touching[i] || now_s - v.last_contact_s < config_.airborne_after_s;
    if (grounded != v.on_ground) {
      v.on_ground = grounded;
      if (!v.crashed) {
        record(grounded ? EventType::kTouchdown : EventType::kTakeoff, static_cast<int>(i), "");
      }
    }
  }
}

void Simulation::kill_vehicle(size_t vehicle, const std::string& reason) {
  VehicleRuntime& v = vehicles_[vehicle];
  if (v.crashed) return;
  v.crashed = true;
  v.fc.disarm(true);
  std::fill(v.motor_cmd.begin(), v.motor_cmd.end(), 0.0);
  record(EventType::kCrash, static_cast<int>(vehicle), reason);
}

void Simulation::set_motor_failed(size_t vehicle, size_t rotor, bool failed) {
  VehicleRuntime& v = vehicles_[vehicle];
  if (rotor >= v.motors.failed.size()) return;
  v.motors.failed[rotor] = failed;
  record(EventType::kMotorFailure, static_cast<int>(vehicle),
         "rotor " + std::to_string(rotor) + (failed ? " failed" : " restored"));
}

bool Simulation::post(size_t vehicle, VehicleTask task) {
  if (vehicle >= vehicles_.size()) return false;
  std::lock_guard<std::mutex> lock(tasks_mutex_);
  pending_tasks_[vehicle].push_back(std::move(task));
  tasks_pending_ = true;
  return true;
}

void Simulation::record(EventType type, int vehicle, std::string detail) {
  events_.add(world_->time_s(), type, vehicle, std::move(detail));
}

uint64_t Simulation::state_hash() const {
  uint64_t h = 0xCBF29CE484222325ull;
  const double t = world_->time_s();
  fnv1a(&h, &t, sizeof(t));
  for (size_t i = 0; i < vehicles_.size(); ++i) {
    const fc::TruthState s = world_->truth(i);
    fnv1a(&h, s.position_enu_m.data(), 3 * sizeof(double));
    fnv1a(&h, s.q_enu_body.coeffs().data(), 4 * sizeof(double));
    fnv1a(&h, s.velocity_enu_m_s.data(), 3 * sizeof(double));
    fnv1a(&h, s.rate_body_rad_s.data(), 3 * sizeof(double));
  }
  return h;
}

}  // namespace uavsim::server::sim
