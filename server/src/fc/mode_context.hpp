// What a flight mode may see and do: the ModeContext, and the small state structs it is a view of.
//
// A mode reads the estimate, the time, the parameters, home and the flight state (armed, landed,
// taking off); it sets the cascade's command for this step (CascadeCommand), the heading
// (YawState), the carrot and the points it holds and lands at (NavState), GUIDED's targets
// (GuidedState) and the mission's current item and reached queue (MissionState); it flies with the
// context's services: the carrot (start_hold, start_nav_to, start_takeoff, run_nav, nav_limits,
// stopping_point, face_destination), the land descent and the pilot's sticks.
// FlightController::Impl owns the structs and builds a context for each call into a mode (a test
// builds one from its own structs, without a controller); the failsafes, the mixers, the motor
// monitor, the sensors, the battery, the link timers and arming stay out of a mode's reach. What a
// mode needs from the cascade below it (a fresh start for a take-off, the collective it gave, the
// mixer's thrust range) goes through the CascadePort.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstddef>
#include <optional>
#include <string_view>
#include <vector>

#include "fc/fc_types.hpp"
#include "fc/params.hpp"
#include "fc/position_control.hpp"
#include "fc/waypoint_nav.hpp"

namespace uavsim::server::fc {

// A fixed-capacity FIFO that drops the oldest entry when full: events raised inside update() are
// queued without allocating.
template <typename T, std::size_t N>
class EventRing {
 public:
  void push(const T& v) {
    items_[(head_ + size_) % N] = v;
    if (size_ < N) {
      ++size_;
    } else {
      head_ = (head_ + 1) % N;
    }
  }
  template <typename F>
  void drain(F&& f) {
    for (std::size_t k = 0; k < size_; ++k) f(items_[(head_ + k) % N]);
    head_ = 0;
    size_ = 0;
  }

 private:
  std::array<T, N> items_{};
  std::size_t head_ = 0;
  std::size_t size_ = 0;
};

// STATUSTEXT payload: at most 50 characters, as in MAVLink.
struct FixedText {
  int severity = 6;
  std::array<char, 51> text{};
};

// The messages for the GCS not yet drained, without allocating.
class StatusTexts {
 public:
  // Queues a text with its MAV_SEVERITY; longer texts are cut at 50 characters.
  void push(int severity, std::string_view text);
  template <typename F>
  void drain(F&& f) {
    ring_.drain(f);
  }

 private:
  EventRing<FixedText, 32> ring_;
};

// How the cascade is driven this step.
enum class ControlKind {
  kIdle,      // armed on the ground: motors at MOT_SPIN_ARM, controllers reset
  kPosition,  // position controller -> attitude -> rates
  kAttitude,  // attitude given (STABILIZE level, GUIDED attitude target), climb rate or thrust
  kBodyRate,  // GUIDED attitude target with body rates only
};

enum class GuidedSub { kHold, kTakeoff, kWp, kPosVelAccel, kVelAccel, kAccel, kAttitude };

// What the active mode asks of the cascade for this step.
struct CascadeCommand {
  ControlKind kind = ControlKind::kIdle;
  PositionSetpoint setpoint;  // kPosition; the climb rate with attitude_climb
  // kAttitude, kBodyRate's fallback; under kPosition the cascade writes its own here
  Eigen::Quaterniond q_attitude_target = Eigen::Quaterniond::Identity();
  Eigen::Vector3d rate_target_body_rad_s = Eigen::Vector3d::Zero();  // kBodyRate
  double fixed_thrust_n = 0.0;  // STABILIZE: collective held from entry
  bool attitude_climb = false;  // kAttitude, kBodyRate: collective from the climb-rate controller
};

// The heading: where yaw should end up, and the command slewed toward it after the mode's step.
struct YawState {
  double target_rad = 0.0;
  double cmd_rad = 0.0;  // what the attitude controller gets
  double rate_ff_rad_s = 0.0;
  double rate_cmd_rad_s = 0.0;  // rate_mode: GUIDED's yaw-rate target or the pilot's yaw stick
  bool rate_mode = false;
  bool fixed = false;                // a commanded heading overrides "face the waypoint"
  double slew_override_rad_s = 0.0;  // CONDITION_YAW rate; 0: ATC_SLEW_YAW
};

// The carrot and the points the modes hold and land at.
struct NavState {
  WaypointNav carrot;
  bool active = false;  // the carrot drives the position setpoint
  Eigen::Vector3d hold_position_enu_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d land_xy_enu_m = Eigen::Vector3d::Zero();  // LAND (RTL's, AUTO's): descent holds
  // speeds set by DO_CHANGE_SPEED until the next mode change (0: the parameter)
  double speed_xy_override_m_s = 0.0;
  double speed_up_override_m_s = 0.0;
  double speed_dn_override_m_s = 0.0;
};

// Armed, on the ground, taking off. Arming, disarming and the land detector set them; a mode only
// reads them, and a take-off it starts leaves the ground.
struct FlightState {
  bool armed = false;
  bool landed = true;  // ArduCopter's land_complete
  bool takeoff_active = false;
};

struct Home {
  Eigen::Vector3d position_enu_m = Eigen::Vector3d::Zero();
  bool set = false;  // at arming, or at the first good fix before
};

// ArduCopter's THR_DZ (100 of the 1000 us throttle range): no climb, and no take-off, within this
// of mid stick.
inline constexpr double kThrottleDeadzone = 0.1;

// The pilot's sticks (RC overrides) as last set.
struct PilotState {
  PilotInput input;
  std::optional<double> time_s;  // when the sticks were last set
  bool flying_xy = false;        // LOITER: the sticks moved the vehicle (hold where it stops)
};

// The sticks if fresh (RC_OVERRIDE_TIME: 0 ignores them, -1 never expires), else nullopt.
std::optional<PilotInput> fresh_pilot_input(const PilotState& pilot, const ParamValues& p,
                                            double now_s);

// GUIDED's targets (SET_POSITION_TARGET_*, SET_ATTITUDE_TARGET) and the sub-mode they chose.
struct GuidedState {
  GuidedSub sub = GuidedSub::kHold;
  GuidedTarget target;
  AttitudeTarget attitude;
  double cmd_time_s = 0.0;  // when the last target arrived
  bool is_new = false;      // a target arrived since the last step
  bool reinit = false;      // ... and it switched the sub-mode
};

// AUTO's mission.
struct MissionState {
  std::vector<MissionItem> items;  // item 0 is home
  int current = 1;
  int last = -1;               // MISSION_START's last item; -1: to the end
  EventRing<int, 64> reached;  // MISSION_ITEM_REACHED, not yet drained
};

// What a mode needs from the cascade below it. FlightController::Impl implements it; a test fakes
// it.
class CascadePort {
 public:
  virtual ~CascadePort() = default;
  // A take-off starts: the position and attitude controllers start fresh, the land detector at 0.
  virtual void restart_for_takeoff() = 0;
  // The collective the mixer gave in the last step (N).
  virtual double collective_n() const = 0;
  // The collective that hovers (m g) and the most the active mixer gives (N).
  virtual double hover_thrust_n() const = 0;
  virtual double max_thrust_n() const = 0;

 protected:
  CascadePort() = default;
  CascadePort(const CascadePort&) = default;
  CascadePort& operator=(const CascadePort&) = default;
};

// The view a mode runs over, built for one call. Holds references: it must not outlive the structs.
class ModeContext {
 public:
  struct Inputs {
    const EstimatedState& estimate;
    double now_s;
    const ParamTable& params;
    const Home& home;
  };
  struct State {
    FlightState& flight;
    CascadeCommand& command;
    YawState& yaw;
    NavState& nav;
    PilotState& pilot;
    GuidedState& guided;
    MissionState& mission;
    StatusTexts& texts;
  };
  ModeContext(const Inputs& in, const State& state, CascadePort& cascade)
      : in_(in), s_(state), cascade_(cascade) {}

  // --- read-only: the estimate, time, parameters, home, the flight state
  const EstimatedState& estimate() const { return in_.estimate; }
  double yaw_enu_rad() const;  // the estimate's heading
  double now() const { return in_.now_s; }
  const ParamValues& params() const { return in_.params.values(); }
  const DerivedParams& derived() const { return in_.params.derived(); }
  const Home& home() const { return in_.home; }
  bool armed() const { return s_.flight.armed; }
  bool landed() const { return s_.flight.landed; }
  bool taking_off() const { return s_.flight.takeoff_active; }
  // the collective the cascade gave in the last step (N)
  double collective_n() const { return cascade_.collective_n(); }

  // --- what the mode sets
  CascadeCommand& command() { return s_.command; }
  YawState& yaw() { return s_.yaw; }
  NavState& nav() { return s_.nav; }
  GuidedState& guided() { return s_.guided; }
  MissionState& mission() { return s_.mission; }
  void status(int severity, std::string_view text) { s_.texts.push(severity, text); }

  // --- the carrot
  // Where the vehicle stops braking at WPNAV_ACCEL (horizontal) and WPNAV_ACCEL_Z (vertical).
  Eigen::Vector3d stopping_point() const;
  // WPNAV_* speeds and accelerations, with the DO_CHANGE_SPEED overrides.
  NavLimits nav_limits() const;
  // Carrot to the stopping point.
  void start_hold();
  // Carrot to destination: from the vehicle when idle, keeping the carrot's state when it runs.
  void start_nav_to(const Eigen::Vector3d& destination);
  // Leaves the ground: the carrot climbs straight up to target_z_enu_m.
  void start_takeoff(double target_z_enu_m);
  // Moves the carrot one step (starting a hold if idle) and sets the position setpoint from it;
  // ends a take-off once the carrot is at altitude and the vehicle close to it.
  void run_nav(double dt_s, const NavLimits& limits);
  // WP_YAW_BEHAVIOR: turn toward the carrot's destination unless a heading is commanded.
  void face_destination();
  // Descends at LAND_SPEED (LAND_SPEED_HIGH high above home) over nav().land_xy_enu_m, holding the
  // horizontal position when hold_xy.
  void run_land_descent(bool hold_xy);

  // --- the pilot's sticks (a mode that reads them)
  // The sticks if fresh (RC_OVERRIDE_TIME), else nullopt.
  std::optional<PilotInput> pilot() const;
  // STABILIZE, ALT_HOLD: the attitude target from the roll and pitch sticks (up to ANGLE_MAX).
  void run_pilot_lean(const PilotInput& in);
  // ALT_HOLD, LOITER: the throttle's climb rate, or hold the altitude where the pilot left it.
  void run_pilot_climb(const PilotInput& in, double dt_s);
  // LOITER: the sticks as a horizontal velocity; false when they are centred (the carrot holds).
  bool run_pilot_loiter(const PilotInput& in, double dt_s);
  // STABILIZE: the collective for a throttle stick (mid stick hovers, full stick is full thrust).
  double pilot_thrust_n(double throttle) const;

 private:
  Inputs in_;
  State s_;
  CascadePort& cascade_;
};

}  // namespace uavsim::server::fc
