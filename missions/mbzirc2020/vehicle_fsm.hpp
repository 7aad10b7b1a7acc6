// The balloon-popping UAV's strategy (seed 7.2, fig. 7.13) as a pure state machine: the event loop
// feeds it what a real drone has (MAVLink telemetry, balloons seen by its camera, GCS messages) at
// a fixed rate and applies what it returns (a GUIDED velocity + heading setpoint, take-off or
// landing, GCS messages). No sockets, clocks or simulator calls: tests drive it with made-up
// inputs.
//
// States, in the seed's order: Preflight -> Take-off -> Go Side Center -> Go Scan Altitude -> Blind
// Scan -> Area Allocation Request -> Pierce -> (Back Off: the seed's "moves backwards ... and
// deallocates the area", a state of its own here) -> Blind Scan ... -> Land. Land is entered from
// any state on the GCS's STATE command. Failed: the vehicle disarmed in the air (motors lost); it
// only reports.
//
// Beyond the seed: TakeOver (GCS STATE command when the other UAV has failed, as on Competition Day
// 2) lifts the own-half rule and, once this side's scans are done, sends the UAV to scan the other
// side. Re-tasking: a UAV whose own scans are done while balloons remain waits in Scans Done (its
// STATUS tells the GCS); the GCS's ReTask sends it, over the balloons, to a line short of the
// arena's middle, from where it scans the other half and pierces what it finds there through the
// GCS's airspace allocator while the other UAV is still at work (without a reply it lands).
#pragma once

#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

#include "messages.hpp"
#include "mission_config.hpp"
#include "touchdown_gate.hpp"
#include "uavsim/mission/flight_command.hpp"
#include "uavsim/mission/vehicle_snapshot.hpp"

namespace uavsim::missions::mbzirc2020 {

enum class VehicleState : uint8_t {
  kPreflight,
  kTakeOff,
  kGoSideCenter,
  kGoScanAltitude,
  kBlindScan,
  kAreaAllocationRequest,
  kPierce,
  kBackOff,
  kLand,
  kLanded,
  kFailed,
  kScansDone,  // own scans done, balloons left: waiting for the GCS (re-task or land)
};
const char* vehicle_state_name(VehicleState s);  // "Blind Scan", ...

// A balloon the camera pipeline confirmed (temporal filter), in the field frame.
struct BalloonSighting {
  int track_id = 0;
  Eigen::Vector3d position_enu_m = Eigen::Vector3d::Zero();  // centre
  double last_seen_s = 0.0;                                  // loop time of the last hit
};

// the telemetry (VehicleSnapshot: MAVLink, world ENU, and the attitude's roll and pitch), the
// camera's sightings, the GCS messages
struct VehicleInputs : uavsim::mission::VehicleSnapshot {
  double now_s = 0.0;
  double roll_rad = 0.0, pitch_rad = 0.0;  // ATTITUDE (NED: right wing down, nose up positive)
  // camera
  std::vector<BalloonSighting> balloons;
  // GCS link: commands and the airspace echoes received since the last step, oldest first
  std::vector<GcsCommand> commands;
  std::vector<std::optional<AirspaceArea>> airspace_replies;
};

// the flight command with its heading, the gimbal's elevation, the GCS messages, the note
struct VehicleOutputs : uavsim::mission::FlightCommand {
  double yaw_enu_rad = 0.0;  // kVelocity
  // the gimbal's wanted elevation (negative: down); level while piercing, so that the balloon stays
  // in view up to the blades, a few degrees down otherwise (mission_config.hpp)
  double camera_pitch_rad = 0.0;
  // GCS messages to publish: an airspace request / release (nullopt inside), a popped balloon
  std::optional<std::optional<AirspaceArea>> airspace;
  std::optional<Eigen::Vector2d> popped_enu_m;
  // a line for the log when something happened (state change, target chosen, ...), else empty
  std::string note;
};

class VehicleFsm {
 public:
  // index 0 is "S0" (scans low first, lands via the low transit altitude), 1 is "S1".
  VehicleFsm(const MissionConfig& config, int index, Side side,
             const Eigen::Vector2d& landing_spot_enu_m);

  // (inputs at now_s) => (setpoint, GCS messages). Call at a fixed rate (10-20 Hz).
  VehicleOutputs step(const VehicleInputs& in);

  VehicleState state() const { return state_; }
  Side side() const { return side_; }
  int popped() const { return popped_; }
  bool take_over() const { return take_over_; }
  bool crossing() const { return cross_; }

 private:
  struct ScanWaypoint {
    double x_m;
    double altitude_m;
  };
  VehicleOutputs decide(const VehicleInputs& in);
  // decide()'s steps before the state's own: heights above the take-off spot, the GCS's commands
  // and the motors lost in the air (these two return true when they have settled the step)
  VehicleInputs above_take_off_spot(const VehicleInputs& raw);
  bool apply_gcs_commands(const VehicleInputs& raw, VehicleOutputs& out);
  bool motors_lost(const VehicleInputs& in, VehicleOutputs& out);
  // one handler per state: what the state commands this step, and the transition out of it
  void on_take_off(const VehicleInputs& in, VehicleOutputs& out);
  void on_go_side_center(const VehicleInputs& in, VehicleOutputs& out);
  void on_go_scan_altitude(const VehicleInputs& in, VehicleOutputs& out);
  void on_blind_scan(const VehicleInputs& in, VehicleOutputs& out);
  void on_scans_done(const VehicleInputs& in, VehicleOutputs& out);
  void on_area_allocation_request(const VehicleInputs& in, VehicleOutputs& out);
  void on_pierce(const VehicleInputs& in, VehicleOutputs& out);
  void on_back_off(const VehicleInputs& in, VehicleOutputs& out);
  void on_land(const VehicleInputs& in, VehicleOutputs& out);
  // Blind Scan past its last waypoint: the other half (taken over), the own half again from
  // beyond the middle, Scans Done, or Land
  void end_of_scan_plan(const VehicleInputs& in, VehicleOutputs& out);
  // the target's newest sighting (a new track close to it is the same balloon)
  void follow_target(const VehicleInputs& in);
  // a pierce's target becomes a balloon seen in its way, nearer than the target; returns the note
  std::string take_balloon_in_the_way(const VehicleInputs& in);
  // Pierce's setpoint (blades at the balloon's height, towards it); returns how far the blades
  // are past its centre along the pierce
  double steer_pierce(const VehicleInputs& in, VehicleOutputs& out);
  Eigen::Vector3d back_off_goal(const Eigen::Vector3d& p) const;
  // Land's phases, and its touchdown rule (which keeps the descent's own state)
  void land_climb_to_transit(const VehicleInputs& in, VehicleOutputs& out);
  void land_to_spot(const VehicleInputs& in, VehicleOutputs& out);
  void land_align_skids(const VehicleInputs& in, VehicleOutputs& out);
  void land_descend(const VehicleInputs& in, VehicleOutputs& out);
  bool touched_down(const VehicleInputs& in, double h, bool pause);
  double landing_transit_altitude_m() const;
  void limit_yaw_rate(const VehicleInputs& in, VehicleOutputs& out);
  void enter(VehicleState s, VehicleOutputs& out, const std::string& why);
  void plan_scan();
  double line_y_m() const;
  double inward_yaw_rad() const;
  bool in_own_half(const Eigen::Vector3d& p) const;
  std::optional<BalloonSighting> choose_target(const VehicleInputs& in) const;
  void request_airspace(const VehicleInputs& in, const BalloonSighting& b, VehicleOutputs& out);
  Eigen::Vector3d toward(const Eigen::Vector3d& p, const Eigen::Vector3d& target,
                         double max_speed_m_s) const;
  void hover(const VehicleInputs& in, VehicleOutputs& out, double yaw_enu_rad) const;
  // the transitions that set a state up (its entry actions)
  void start_landing(VehicleOutputs& out, const std::string& why);
  void start_crossing(VehicleOutputs& out, const std::string& why);  // the other half, re-planned
  void start_pierce(const VehicleInputs& in, VehicleOutputs& out);
  // Back Off's end: airspace released, the balloon counted popped if the blades got there
  void end_back_off(VehicleOutputs& out);

  MissionConfig config_;
  int index_;
  Side side_;
  Side home_side_;
  Eigen::Vector2d landing_spot_enu_m_;
  VehicleState state_ = VehicleState::kPreflight;
  double state_since_s_ = 0.0;
  double now_s_ = 0.0;
  bool armed_seen_ = false;
  bool take_over_ = false;
  bool other_side_done_ = false;
  bool retask_ = false;     // the GCS's ReTask arrived
  bool cross_ = false;      // scanning the other half from the middle (re-tasked)
  bool look_home_ = false;  // taken over, both halves scanned: the own half from beyond the middle
  int popped_ = 0;
  double ground_z_m_ =
      0.0;  // the estimator's height on the ground before take-off, less rest height
  std::vector<Eigen::Vector3d> popped_at_;  // as seen, their centres' heights included (poles)

  std::vector<ScanWaypoint> scan_;
  size_t scan_leg_ = 0;
  double hold_altitude_m_ = 0.0;

  // the balloon being requested / pierced
  BalloonSighting target_;
  std::optional<AirspaceArea> request_;
  bool airspace_held_ = false;
  Eigen::Vector3d pierce_start_enu_m_ = Eigen::Vector3d::Zero();
  Eigen::Vector2d coast_dir_ = Eigen::Vector2d::UnitY();
  Eigen::Vector2d pierce_dir_ = Eigen::Vector2d::UnitY();  // towards the target at the start
  double closest_blade_m_ = 1e9;
  bool pierce_reached_ = false;
  bool pierce_level_camera_ = false;
  bool seen_again_ = false;
  double look_back_since_s_ = -1.0;  // back on the line, looking for the balloon since then

  // landing: climb, transit, skids along the wind, descend, motors off
  enum class LandPhase { kClimbToTransit, kToSpot, kAlignSkids, kDescend, kMotorsOff };
  LandPhase land_phase_ = LandPhase::kClimbToTransit;
  double descent_stopped_s_ = -1.0;  // since when the descent has stopped near the ground
  double steady_descent_s_ = -1.0;   // since when it has been a steady ~0.5 m/s descent
  bool steady_descent_ = false;      // a second of it, unbroken, since the last sink
  TouchdownGate touchdown_gate_;     // the last metres wait for calm, skids along the wind
  bool descent_paused_ = false;
  double stop_rule_from_s_ = 0.0;  // a descent resumed from a pause is not "stopped" before this
  double descent_since_s_ = 0.0;   // over the spot since
  double landing_yaw_rad_ = 0.0;   // the heading of the descent: skids along the wind

  // the heading setpoint last sent and when (NaN: none yet), for its rate limit
  double yaw_cmd_rad_ = 0.0;
  double yaw_cmd_s_ = -1.0;
};

}  // namespace uavsim::missions::mbzirc2020
