// ArduCopter-like flight-controller emulation for one vehicle (seed ch. 4.1): seeded sensor models, an
// estimator, the cascade position -> velocity -> acceleration -> attitude -> rate -> mixer, ArduCopter
// modes, arming checks, take-off, landing detection with auto-disarm, GCS-loss and battery failsafes,
// and a live parameter table with ArduPilot names.
//
// A pure library: no MuJoCo, no sockets, no clocks (time is passed in). One instance per vehicle; all
// methods are loop-thread only (the sim loop calls them at control-step boundaries, in vehicle order).
// Commands are the one path that both the in-process API and the MAVLink endpoint drive.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "airframe/airframe.hpp"
#include "fc/fc_types.hpp"
#include "fc/params.hpp"

namespace uavsim::server::fc {

class FlightController {
 public:
  // Builds the controller for an airframe (the mixer is derived from its rotor layout); seed feeds the
  // sensor-noise generators, so equal seeds give equal noise sequences.
  FlightController(const airframe::AirframeParams& airframe, uint64_t seed);
  ~FlightController();
  FlightController(FlightController&&) noexcept;
  FlightController& operator=(FlightController&&) noexcept;

  // One control step at sim time time_s: sample the sensors from truth, update the estimator, run the
  // mode logic and the cascade, write one motor command in [0, 1] per rotor into motor_cmd.
  // Disarmed: all commands 0.
  void update(double time_s, const TruthState& truth, const airframe::BatteryState& battery,
              double* motor_cmd);

  // --- commands (ArduCopter semantics, as MAVLink carries them: docs/mavlink.md §4) ---
  CommandResult arm(bool force);  // force skips the pre-arm checks (MAVLink param2 = 2989 or 21196)
  CommandResult disarm(bool force);  // not forced: only on the ground
  CommandResult set_mode(Mode mode);
  CommandResult takeoff(double altitude_above_home_m);  // armed, landed, GUIDED/LOITER/ALT_HOLD
  CommandResult set_guided_target(const GuidedTarget& target);  // GUIDED only; velocity targets time out
  CommandResult set_attitude_target(const AttitudeTarget& target);  // GUIDED only
  // Holds a commanded heading (armed only): yaw_enu_rad absolute, or added to the current yaw target when
  // relative, slewed at rate_rad_s (0: ATC_SLEW_YAW). kInvalid for a non-finite yaw or a negative rate.
  CommandResult set_yaw(const YawCommand& command);
  // Overrides one speed limit until the next mode change; kInvalid outside (0, 50] m/s.
  CommandResult change_speed(SpeedLimit limit, double speed_m_s);
  // Pilot sticks, as ArduCopter reads its RC channels: STABILIZE leans by them (up to ANGLE_MAX) with
  // throttle as collective (mid stick = hover); ALT_HOLD leans too, with throttle as climb rate;
  // LOITER takes them as horizontal velocity (up to WPNAV_SPEED) and climb rate, and holds position when
  // they are centred. Yaw stick: yaw rate up to ATC_RATE_Y_MAX. Throttle above mid stick takes off in
  // these modes. Input older than RC_OVERRIDE_TIME seconds counts as centred sticks and mid throttle
  // (0: ignored; -1: never expires). kInvalid for non-finite or out-of-range values.
  CommandResult set_pilot_input(const PilotInput& input, double time_s);
  CommandResult land();  // = set_mode(kLand)
  CommandResult rtl();   // = set_mode(kRtl)

  // --- mission (AUTO) ---
  void set_mission(std::vector<MissionItem> items);  // item 0 is home, as in ArduPilot
  const std::vector<MissionItem>& mission() const;
  CommandResult mission_start(int first_item, int last_item);  // MAV_CMD_MISSION_START
  CommandResult set_mission_current(int seq);
  int mission_current() const;
  std::vector<int> drain_reached_items();  // seqs reached since the last call (MISSION_ITEM_REACHED)

  // --- parameters (ArduPilot names where one exists, e.g. WPNAV_SPEED, PSC_POSXY_P, ATC_RAT_RLL_P) ---
  std::optional<double> param(std::string_view name) const;
  std::optional<ParamKind> param_kind(std::string_view name) const;  // its storage type
  CommandResult set_param(std::string_view name, double value);  // kInvalid: unknown name or bad value
  const std::vector<std::string>& param_names() const;  // a fixed order: the MAVLink param_index

  // --- link supervision and faults ---
  void on_gcs_heartbeat(double time_s);  // arms the GCS-loss failsafe (FS_GCS_ENABLE) once seen
  void set_gps_denied(bool denied);      // no fixes until cleared
  void set_gps_glitch(const Eigen::Vector3d& offset_enu_m);  // adds an offset to every fix

  // --- state for telemetry ---
  Mode mode() const;
  bool armed() const;
  LandedState landed_state() const;
  const EstimatedState& estimate() const;
  Eigen::Vector3d home_enu_m() const;      // set when arming (or first GPS fix)
  bool home_set() const;
  std::optional<GuidedTarget> current_target() const;  // what the position controller chases
  double yaw_target_enu_rad() const;
  bool prearm_ok() const;                  // all pre-arm checks pass now
  std::vector<StatusText> drain_status_texts();  // "Arming motors", "Mode change failed", ...
  // How many update() calls got non-finite truth or battery input (they were skipped, the previous
  // motor commands were repeated); telemetry exposes it as a warning counter.
  uint64_t nonfinite_input_count() const;

  struct Impl;  // library internal (fc_impl.hpp); the flight modes see it through a ModeContext

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace uavsim::server::fc
