// Private state of FlightController, shared by its implementation files (flight_controller.cpp:
// commands and the control step; modes.cpp: the rules the modes share and the services they fly with;
// flight_modes.cpp: one object per mode; safety.cpp: arming checks, land detector, failsafes). It is the
// vehicle context the mode objects run over. Not part of the public API.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <optional>
#include <string_view>
#include <vector>

#include "airframe/airframe.hpp"
#include "fc/attitude_control.hpp"
#include "fc/estimator.hpp"
#include "fc/fc_types.hpp"
#include "fc/flight_controller.hpp"
#include "fc/flight_modes.hpp"
#include "fc/mixer.hpp"
#include "fc/motor_monitor.hpp"
#include "fc/params.hpp"
#include "fc/position_control.hpp"
#include "fc/sensors.hpp"
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

// How the cascade is driven this step.
enum class ControlKind {
  kIdle,            // armed on the ground: motors at MOT_SPIN_ARM, controllers reset
  kPosition,        // position controller -> attitude -> rates
  kAttitude,        // attitude given (STABILIZE level, GUIDED attitude target), climb rate or thrust
  kBodyRate,        // GUIDED attitude target with body rates only
};

enum class GuidedSub { kHold, kTakeoff, kWp, kPosVelAccel, kVelAccel, kAccel, kAttitude };

struct FlightController::Impl {
  explicit Impl(const airframe::AirframeParams& airframe, uint64_t seed);

  // --- flight_controller.cpp ---
  void update(double time_s, const TruthState& truth, const airframe::BatteryState& battery,
              double* motor_cmd);
  void run_cascade(double dt_s);
  void update_yaw(double dt_s);
  void monitor_motors(double dt_s);
  const Mixer& active_mixer() const {
    return lost_motor_ >= 0 ? *degraded_mixers_[static_cast<std::size_t>(lost_motor_)] : mixer_;
  }
  void status(int severity, std::string_view text) const;
  void set_home(const Eigen::Vector3d& home);
  double now() const { return last_time_s_; }
  NavLimits nav_limits() const;
  // the pilot's sticks if fresh (RC_OVERRIDE_TIME) in a mode that reads them
  std::optional<PilotInput> pilot() const;

  // --- modes.cpp ---
  bool enter_mode(Mode mode, bool from_failsafe);
  void run_mode(double dt_s);
  void start_hold();                      // carrot to the stopping point
  void start_nav_to(const Eigen::Vector3d& destination);
  void start_takeoff(double target_z_enu_m);
  void run_nav(double dt_s, const NavLimits& limits);
  void run_land_descent(bool hold_xy);
  bool pilot_takeoff();                       // armed on the ground, throttle up in a pilot mode
  void run_pilot_lean(const PilotInput& in);  // STABILIZE, ALT_HOLD: attitude from the sticks
  void run_pilot_climb(const PilotInput& in, double dt_s);    // ALT_HOLD, LOITER: the z setpoint
  bool run_pilot_loiter(const PilotInput& in, double dt_s);  // LOITER: false when the sticks are centred
  double pilot_thrust_n(double throttle) const;
  void face_destination();
  Eigen::Vector3d stopping_point() const;
  bool gps_mode(Mode mode) const;

  // --- safety.cpp ---
  bool prearm_checks(bool report) const;
  void init_mode_state();
  void run_land_detector(double dt_s);
  void run_failsafes();
  void do_disarm(std::string_view why);
  void on_touchdown();

  // configuration
  airframe::AirframeParams airframe_;
  double mass_kg_ = 0.0;
  double hover_thrust_n_ = 0.0;
  Eigen::Matrix3d inertia_ = Eigen::Matrix3d::Identity();
  ParamTable params_;
  Mixer mixer_;
  // one degraded mixer per rotor that could be lost (vehicles with MotorMonitor::kMinRotors or more),
  // built up front so a detection in flight allocates nothing; nullopt: that loss is not flyable
  std::vector<std::optional<Mixer>> degraded_mixers_;
  MotorMonitor motor_monitor_;
  int lost_motor_ = -1;  // the rotor the degraded mixer leaves out, or -1

  // sensing and estimation
  Sensors sensors_;
  SensorFrame frame_;
  Estimator estimator_;
  airframe::BatteryState battery_;

  // controllers
  PositionController pos_ctrl_;
  AttitudeController att_ctrl_;
  WaypointNav nav_;
  PositionSetpoint sp_;
  ControlKind control_ = ControlKind::kIdle;
  Eigen::Quaterniond q_attitude_target_ = Eigen::Quaterniond::Identity();
  Eigen::Vector3d rate_target_body_rad_s_ = Eigen::Vector3d::Zero();
  double fixed_thrust_n_ = 0.0;   // STABILIZE: collective held from entry
  bool attitude_climb_ = false;   // kAttitude: collective from the climb-rate controller
  MixerStatus mixer_status_;
  double collective_demand_n_ = 0.0;  // before the mixer's desaturation
  std::array<double, kMaxRotors> motor_cmd_{};
  std::array<double, kMaxRotors> rotor_thrust_n_{};

  // time
  double last_time_s_ = 0.0;
  bool have_time_ = false;

  // vehicle state
  Mode mode_ = Mode::kStabilize;
  FlightModes modes_;  // one object per mode; mode_ names the active one
  FlightMode& active_mode() { return modes_.of(mode_); }
  const FlightMode& active_mode() const { return modes_.of(mode_); }
  bool armed_ = false;
  bool landed_ = true;          // ArduCopter's land_complete
  bool takeoff_active_ = false;
  double landed_since_s_ = 0.0;
  double land_detect_s_ = 0.0;  // how long the land-detector conditions have held
  Eigen::Vector3d home_enu_m_ = Eigen::Vector3d::Zero();
  bool home_set_ = false;

  // yaw
  double yaw_target_rad_ = 0.0;  // where yaw should end up
  double yaw_cmd_rad_ = 0.0;     // slewed toward the target; what the attitude controller gets
  double yaw_rate_ff_rad_s_ = 0.0;
  double yaw_rate_cmd_rad_s_ = 0.0;  // GUIDED yaw-rate target
  bool yaw_rate_mode_ = false;
  bool yaw_fixed_ = false;          // a commanded heading overrides "face the waypoint"
  double yaw_slew_override_rad_s_ = 0.0;  // CONDITION_YAW rate; 0: ATC_SLEW_YAW

  // speeds set by DO_CHANGE_SPEED (0: parameter)
  double speed_xy_override_m_s_ = 0.0;
  double speed_up_override_m_s_ = 0.0;
  double speed_dn_override_m_s_ = 0.0;

  // GUIDED
  GuidedSub guided_sub_ = GuidedSub::kHold;
  GuidedTarget guided_target_;
  AttitudeTarget attitude_target_;
  double guided_cmd_time_s_ = 0.0;
  bool guided_new_ = false;     // a target arrived since the last step
  bool guided_reinit_ = false;  // ... and it switched the guided sub-mode
  bool nav_active_ = false;  // the carrot drives the position setpoint

  // the pilot (RC overrides)
  PilotInput pilot_;
  std::optional<double> pilot_time_s_;  // when the sticks were last set
  bool pilot_flying_xy_ = false;        // LOITER: the sticks moved the vehicle (hold where it stops)
  Eigen::Vector3d hold_position_enu_m_ = Eigen::Vector3d::Zero();

  // LAND (and RTL's and AUTO's landings): where the descent holds
  Eigen::Vector3d land_xy_enu_m_ = Eigen::Vector3d::Zero();

  // AUTO
  std::vector<MissionItem> mission_;
  int mission_current_ = 1;
  int mission_last_ = -1;  // MISSION_START last item; -1: to the end
  EventRing<int, 64> reached_;

  // link and failsafes
  bool gcs_seen_ = false;
  double last_gcs_heartbeat_s_ = 0.0;
  bool fs_gcs_active_ = false;
  bool fs_batt_triggered_ = false;
  double gps_lost_since_s_ = -1.0;
  bool fs_ekf_active_ = false;
  bool estimator_converged_ = false;

  mutable EventRing<FixedText, 32> texts_;  // mutable: const checks may report
  uint64_t nonfinite_inputs_ = 0;
};

}  // namespace uavsim::server::fc
