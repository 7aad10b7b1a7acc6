// The MBZIRC 2017 landing FSM (seed 7.1, fig. 7.6): Start -> Go To Centre -> Intercept -> Wait
// Until Visible -> Approach -> Landed. Pure: each step takes what the UAV knows (its telemetry, its
// pad switches and what its camera pipeline made of the truck) and returns one command; no I/O, no
// clock.
#pragma once

#include <Eigen/Core>
#include <limits>
#include <optional>
#include <string>

#include "clearance_envelope.hpp"
#include "funnel.hpp"
#include "mission_config.hpp"
#include "uavsim/client/pid.hpp"
#include "uavsim/mission/flight_command.hpp"

namespace uavsim::missions::mbzirc2017 {

enum class LandingState { kStart, kGoToCentre, kIntercept, kWaitUntilVisible, kApproach, kLanded };
const char* landing_state_name(LandingState s);

// What the camera pipeline knows about the truck at the step's time (truck_perception.hpp).
struct TruckKnowledge {
  bool initialised = false;  // the Kalman filter has started (two points)
  Eigen::Vector2d position_enu_m = Eigen::Vector2d::Zero();  // the marker, extrapolated to now
  Eigen::Vector2d velocity_enu_m_s = Eigen::Vector2d::Zero();
  // the track was made before a step of the UAV's own position estimate and a new one has not
  // started yet (TruckPerception::on_estimate_step): the velocity, heading and yaw rate hold, the
  // position is up to the step's size off
  bool position_stale = false;
  double heading_enu_rad = 0.0;  // the truck's forward direction (the track's, by its way)
  double yaw_rate_rad_s = 0.0;   // its turning rate on the track's curve (positive left)
  double last_seen_s = -std::numeric_limits<double>::infinity();  // stamp of the newest sighting
  std::optional<Eigen::Vector2d> interception_enu_m;  // the best meeting point at cruise speed
  double interception_time_to_go_s = 0.0;
};

struct FsmInputs {
  double now_s = 0.0;
  bool armed = false;
  Eigen::Vector3d position_enu_m = Eigen::Vector3d::Zero();  // telemetry (body origin)
  Eigen::Vector3d velocity_enu_m_s = Eigen::Vector3d::Zero();
  bool switch_closed = false;  // any landing-pad microswitch
  bool camera_dark = false;    // the newest camera frame was black (a blinded or failed camera)
  // the FC's position estimate stepped lately (a GPS jump being blended in: estimate_monitor.hpp):
  // its position and velocity are off by up to metres and metres per second meanwhile
  bool estimate_settling = false;
  TruckKnowledge truck;
};

// the flight command (the heading is held by the program), then the FSM's note
struct FsmOutputs : uavsim::mission::FlightCommand {
  std::string note;  // a progress line, when something happened
};

class LandingFsm {
 public:
  explicit LandingFsm(const MissionConfig& config);

  FsmOutputs step(const FsmInputs& in);

  LandingState state() const { return state_; }
  int misses() const { return misses_; }
  // Climb-aways begun so far (the clearance envelope's aborts).
  int climb_aways() const { return climb_aways_; }
  // Whether a climb-away is under way.
  bool climbing_away() const { return climb_away_; }
  // skids above the deck for a body origin at z
  double height_above_deck_m(double z_enu_m) const;

 private:
  void enter(LandingState s, double now_s, FsmOutputs* out, const std::string& why);
  // horizontal velocity towards a point at up to speed, with altitude held at altitude_m
  Eigen::Vector3d fly_to(const FsmInputs& in, const Eigen::Vector2d& target_enu_m, double speed_m_s,
                         double altitude_m) const;
  double hold_altitude_m_s(const FsmInputs& in, double altitude_m) const;
  // one handler per state before the Approach; each returns true when it has commanded the step,
  // false when it has handed over to the next state (which then acts in the same step)
  void on_start(const FsmInputs& in, FsmOutputs& out);
  bool on_go_to_centre(const FsmInputs& in, FsmOutputs& out);
  bool on_intercept(const FsmInputs& in, FsmOutputs& out);
  bool on_wait_until_visible(const FsmInputs& in, FsmOutputs& out);
  FsmOutputs approach(const FsmInputs& in);
  // the Approach's view of the truck this step: the skids' height above the deck, the truck as
  // estimated, the UAV in its frame and what the clearance envelope says of it
  struct ApproachView {
    double h = 0.0;
    EstimatedTruck truck;
    TruckRelative rel;
    EnvelopeCheck check;
  };
  // a climb-away under way: true once clear of the truck (a new approach goes on in this step)
  bool end_climb_away(const FsmInputs& in, const ApproachView& view, FsmOutputs& out);
  // the Approach's horizontal velocity: the truck's plus the PID's correction towards the marker
  Eigen::Vector2d approach_velocity_xy(const FsmInputs& in, bool blind_low);
  // the Approach's climb rate with the marker in sight, in the blind last metres, or lost; nullopt
  // when the rule ended the approach (a climb-away, Go To Centre), its command then in out
  std::optional<double> descent_in_sight_m_s(const FsmInputs& in, const ApproachView& view,
                                             FsmOutputs& out);
  std::optional<double> descent_blind_m_s(const FsmInputs& in, const ApproachView& view,
                                          FsmOutputs& out);
  std::optional<double> climb_when_lost_m_s(const FsmInputs& in, double h, FsmOutputs& out);
  // begins the climb-away (then Go To Centre if give_up, else a new approach) and commands it
  FsmOutputs climb_away(const FsmInputs& in, const EstimatedTruck& truck, const TruckRelative& rel,
                        const std::string& why, bool give_up);
  bool seen_since(const FsmInputs& in, double since_s) const;
  // in the blind last metres: the skids' height above the deck from where the marker left the
  // image (marker_lost_height_m) less the barometric descent since, not the barometer's absolute
  // altitude (its drift is tenths of a metre)
  double blind_height_m(const FsmInputs& in) const;
  // the Approach while the FC's estimate settles after a step: no descent on it and no correction
  // towards the marker from it (FsmInputs::estimate_settling)
  FsmOutputs approach_while_settling(const FsmInputs& in, double h);
  // the Approach after a step, settled, until the truck's track is made again from new sightings
  // (TruckKnowledge::position_stale): no descent, no correction towards the old track's marker
  FsmOutputs approach_while_rebuilding(const FsmInputs& in, double h);

  MissionConfig config_;
  Funnel funnel_;
  ClearanceEnvelope envelope_;
  LandingState state_ = LandingState::kStart;
  double entered_s_ = 0.0;
  double last_step_s_ = -1.0;
  double step_dt_s_ = 0.0;
  bool takeoff_sent_ = false;
  double takeoff_sent_s_ = 0.0;
  int misses_ = 0;
  // Approach
  client::Pid pid_x_, pid_y_;
  std::optional<double> lost_since_s_;
  std::optional<double> open_loop_since_s_;
  bool outside_reported_ = false;
  bool open_loop_reported_ = false;
  bool ready_for_open_loop_ = false;  // at the last sighting: centred and matched in the deck box
  bool climb_away_ = false;
  bool settling_reported_ = false;
  std::optional<double> rebuilding_since_s_;
  double open_loop_start_z_m_ = 0.0;  // the estimate's altitude as the blind last metres began
  bool give_up_after_climb_ = false;
  int climb_aways_ = 0;
};

}  // namespace uavsim::missions::mbzirc2017
