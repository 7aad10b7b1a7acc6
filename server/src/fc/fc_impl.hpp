// Private state of FlightController, shared by its implementation files (flight_controller.cpp:
// commands and the control step; modes.cpp: the rules the modes share; safety.cpp: arming checks,
// land detector, failsafes). The state the flight modes fly with is grouped in the small structs of
// mode_context.hpp (flight state, home, cascade command, yaw, carrot, pilot, GUIDED, mission,
// status texts); mode_context() builds the modes' narrow view of them, and the rest (mixers, motor
// monitor, sensors, estimator, battery, link and failsafe timers) stays here, out of the modes'
// reach. Not part of the public API.
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
#include "fc/mode_context.hpp"
#include "fc/motor_monitor.hpp"
#include "fc/params.hpp"
#include "fc/position_control.hpp"
#include "fc/sensors.hpp"
#include "fc/waypoint_nav.hpp"

namespace uavsim::server::fc {

struct FlightController::Impl final : CascadePort {
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
  void status(int severity, std::string_view text) const { texts_.push(severity, text); }
  void set_home(const Eigen::Vector3d& home);
  double now() const { return last_time_s_; }
  // the pilot's sticks if fresh (RC_OVERRIDE_TIME) in a mode that reads them
  std::optional<PilotInput> pilot() const;
  // the modes' view of the vehicle, for one call into a mode or a carrot service
  ModeContext mode_context();

  // CascadePort: what a mode needs from the cascade
  void restart_for_takeoff() override;
  double collective_n() const override { return mixer_status_.thrust_n; }
  double hover_thrust_n() const override { return hover_thrust_n_; }
  double max_thrust_n() const override { return active_mixer().max_total_thrust_n(); }

  // --- modes.cpp ---
  bool enter_mode(Mode mode, bool from_failsafe);
  void init_mode_state();  // the common resets, then the active mode's enter()
  void run_mode(double dt_s);
  bool pilot_takeoff();              // armed on the ground, throttle up in a pilot mode
  void start_mission_item(int seq);  // AUTO: MISSION_START, MISSION_SET_CURRENT, a new mission
  bool gps_mode(Mode mode) const;

  // --- safety.cpp ---
  bool prearm_checks(bool report) const;
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
  CascadeCommand command_;  // what the mode asks of the cascade this step
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
  FlightState flight_;  // armed, landed, taking off
  double landed_since_s_ = 0.0;
  double land_detect_s_ = 0.0;  // how long the land-detector conditions have held
  Home home_;

  // the state the modes fly with (mode_context.hpp)
  YawState yaw_;
  NavState nav_;
  GuidedState guided_;
  PilotState pilot_;
  MissionState mission_;

  // link and failsafes
  bool gcs_seen_ = false;
  double last_gcs_heartbeat_s_ = 0.0;
  bool fs_gcs_active_ = false;
  bool fs_batt_triggered_ = false;
  double gps_lost_since_s_ = -1.0;
  bool fs_ekf_active_ = false;
  bool estimator_converged_ = false;

  mutable StatusTexts texts_;  // mutable: const checks may report
  uint64_t nonfinite_inputs_ = 0;
};

}  // namespace uavsim::server::fc
