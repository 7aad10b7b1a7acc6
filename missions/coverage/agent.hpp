// One agent of the coverage flock as a pure state machine (the thesis the project descends from,
// chapter 3 and fig. 4.6). The program around it feeds it, at a fixed rate, what a real drone has
// (its own telemetry and the radio frames it heard) and applies what it returns (take-off, a
// velocity + yaw-rate setpoint, landing, radio frames to broadcast). No sockets, clocks or
// simulator calls: the tests fly several of them over a point-mass model.
//
// States (fig. 4.6): Taking Off -> Querying (leader) or Non-Leader; the leader cycles Querying ->
// Deploying -> Running -> Waiting -> Querying until the query finds the rectangle covered, then
// Going Home (broadcast, which sends every agent home) -> Landed. A leader that hears a lower id
// becomes Non-Leader; a Non-Leader whose leader aged out of its ADB and that has the lowest id left
// becomes the leader and queries. Failed (beyond the figure): the agent's own vehicle stopped
// flying (disarmed or crashed in the air): it goes silent.
// Beyond the figure, losses on the way home: agents that land keep their radios on (they beacon
// "landed", relay and answer queries, and no longer lead). When an agent that had not landed ages
// out during Going Home, the leader (the lowest id still flying) queries the flock's map again,
// near home once agents have landed. The leader lands last (it hovers low over its home until
// every agent it hears has landed), so a loss during the others' descent is noticed too. If the
// rectangle is no longer covered, it starts the next survey round (a counter in the beacons): the
// agents still flying leave Going Home for Non-Leader and the leader plans over what was lost.
// Otherwise everyone lands as before.
#pragma once

#include <Eigen/Core>
#include <array>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "agents_database.hpp"
#include "aggregation.hpp"
#include "area_parts.hpp"
#include "coverage_config.hpp"
#include "flocking.hpp"
#include "path_planner.hpp"
#include "radio_messages.hpp"
#include "radio_pacer.hpp"
#include "uavsim/mission/vehicle_snapshot.hpp"

namespace uavsim::missions::coverage {

enum class AgentState : uint8_t {
  kTakingOff,
  kQuerying,
  kDeploying,
  kRunning,
  kWaiting,
  kNonLeader,
  kGoingHome,
  kLanded,
  kFailed,
};
inline constexpr int kAgentStateCount = 9;
const char* agent_state_name(AgentState s);  // "Taking Off", ...

// the telemetry (VehicleSnapshot: MAVLink, world ENU), then the radio
struct AgentInputs : uavsim::mission::VehicleSnapshot {
  double now_s = 0.0;
  // radio frames heard since the last step, in arrival order
  std::vector<Frame> received;
  // optimised variant (3.6): the ground station's latest map, if one arrived
  std::optional<AreaParts> gcs_map;
};

struct AgentOutputs {
  enum class Action { kNone, kTakeOff, kVelocity, kLand };
  Action action = Action::kNone;
  Eigen::Vector3d velocity_enu_m_s = Eigen::Vector3d::Zero();  // kVelocity
  double yaw_rate_rad_s = 0.0;                                 // kVelocity, ENU (CCW positive)
  // kVelocity: the heading R2 turns towards (ENU), when there is one. An autopilot with its own
  // yaw controller (ArduCopter's GUIDED) is better given this than the rate: R2's gain on top of
  // the autopilot's yaw lag and the telemetry delay makes the heading oscillate.
  std::optional<double> yaw_enu_rad;
  double takeoff_altitude_m = 0.0;  // kTakeOff
  std::vector<Frame> broadcast;     // radio frames to send now
  std::optional<Picture> picture;   // a picture taken at this step
  std::string note;                 // a log line when something happened
};

class Agent {
 public:
  // config must validate(); id in [0, kMaxAgents); home is the take-off point (world ENU); frames:
  // the radio's frame size (fit_frames() of the channel's largest frame; the default is 802.15.4's
  // 127 bytes).
  Agent(const CoverageConfig& config, int id, const Eigen::Vector2d& home_enu_m,
        const FrameFit& frames = FrameFit{});

  // (inputs at now_s) => (setpoint, frames). Call at a fixed rate (10-20 Hz).
  AgentOutputs step(const AgentInputs& in);

  int id() const { return id_; }
  AgentState state() const { return state_; }
  int leader() const { return adb_.leader(); }
  const AgentsDatabase& adb() const { return adb_; }
  const AreaParts& own() const { return own_; }
  const AggregationNode& aggregation() const { return aggregation_; }
  // The leader's latest query result (its view of the flock's coverage), if it has one.
  const std::optional<AreaParts>& last_map() const { return last_map_; }
  const std::optional<PlannedPath>& path() const { return path_; }
  bool mission_complete() const { return complete_; }
  // Landed, and every agent this one still hears has landed too: its radio can be switched off.
  // A recall after this agent landed (a later round than the one it went home in) keeps it on
  // until the later round is over: the later round's leader may survey out of radio range, where
  // the landed agents no longer hear it, and needs their pictures when it queries again near home.
  // A loss noticed on the ground keeps it on too, for the check of the lowest id landed; and it
  // stays on kSwitchOffDelay_s after it first saw every agent landed, beaconing and relaying, so
  // that agents beyond its neighbours learn of the last landings before it goes silent (else they
  // would age the last to land out as lost).
  static constexpr double kSwitchOffDelay_s = 5.0;
  bool flock_landed() const {
    return state_ == AgentState::kLanded && all_landed_since_s_ >= 0.0 &&
           last_now_s_ - all_landed_since_s_ >= kSwitchOffDelay_s;
  }
  // The survey round (a recall after a loss on the way home starts the next).
  int round() const { return round_; }
  // Sim seconds spent in each state (fig. 4.9), indexed by AgentState.
  const std::array<double, kAgentStateCount>& time_in_state() const { return time_in_state_; }
  int queries_started() const { return queries_started_; }

 private:
  void enter(AgentState s, AgentOutputs& out, const std::string& why);
  bool is_leader_state() const;
  void receive(const AgentInputs& in);
  void take_picture(const AgentInputs& in, AgentOutputs& out);
  void broadcast(const AgentInputs& in, AgentOutputs& out);
  void run_state(const AgentInputs& in, AgentOutputs& out);
  // run_state's first step in any state: a recall, the going-home broadcast, a change of leader
  void change_role(bool lead, AgentOutputs& out);
  // one handler per state: what the state commands this step, and the transition out of it
  void on_taking_off(const AgentInputs& in, bool lead, AgentOutputs& out);
  void on_querying(const AgentInputs& in, AgentOutputs& out);
  void on_deploying(const AgentInputs& in, AgentOutputs& out);
  void on_running(const AgentInputs& in, AgentOutputs& out);
  void on_waiting(const AgentInputs& in, AgentOutputs& out);
  void on_non_leader(const AgentInputs& in, AgentOutputs& out);
  void on_going_home(const AgentInputs& in, bool lead, AgentOutputs& out);
  // Running after a loss deep inside the line: hold, then back to before the loss
  void run_rewind(const AgentInputs& in, AgentOutputs& out);
  // Going Home with the landing sent: Landed on the ground, Failed if disarmed still descending
  void watch_landing(const AgentInputs& in, AgentOutputs& out);
  // Going Home in its layer: towards home, braking, away from the agents in the same layer
  Eigen::Vector2d home_velocity(const AgentInputs& in, double home_dist) const;
  void start_query(AgentOutputs& out);
  // Running: a record of the line aged out; rewind if its strip lies deep inside the line
  void start_rewind(const AgentInputs& in, const AgentRecord& lost);
  void finish_query(const AgentInputs& in, AgentOutputs& out);
  AreaParts flock_map() const;
  // Going Home, leader: checks the flock's map after a loss; true when it recalled the flock.
  bool verify_after_loss(const AgentInputs& in, AgentOutputs& out);
  // landed: no survey round later than the one we went home in is still flying (its flyers may be
  // out of range, not lost; and it needs our pictures when it queries near home)
  bool no_later_round_surveying() const { return round_ == home_round_ || later_round_over_; }
  // disarmed, but still above the ground or still sinking: not a landing (Going Home)
  bool descending_when_disarmed(const AgentInputs& in) const;
  bool flock_in_line(const AgentInputs& in) const;
  // a velocity setpoint towards `target` (2D) at `speed`, holding the survey altitude
  void fly_to(const AgentInputs& in, const Eigen::Vector2d& target, double speed,
              double heading_rad, AgentOutputs& out) const;
  double altitude_rate(const AgentInputs& in, double altitude_m) const;
  double yaw_rate_to(const AgentInputs& in, double heading_rad) const;

  CoverageConfig config_;
  int id_;
  Eigen::Vector2d home_enu_m_;
  RadioFrameOrigin origin_;
  FrameFit frames_;
  AgentsDatabase adb_;
  AreaParts own_;
  AggregationNode aggregation_;
  AggregateReassembler reassembler_;
  AggregateMessage outgoing_;  // the last message polled (its memory reused by the next)
  Beacon heard_;               // the last beacon decoded (its memory reused by the next)
  FlockController flock_;

  AgentState state_ = AgentState::kTakingOff;
  double state_since_s_ = 0.0;
  double last_now_s_ = -1.0;
  double dt_s_ = 0.0;
  double age_remainder_ms_ = 0.0;
  bool started_ = false;
  bool takeoff_sent_ = false;
  bool land_sent_ = false;
  bool home_reached_ = false;  // Going Home: within kHomeReached_m, until kHomeLeft_m away
  bool airborne_seen_ = false;
  double ground_z_m_ = 0.0;  // where it stood before take-off (ENU z)
  bool going_home_heard_ = false;
  bool complete_ = false;
  // survey rounds and losses on the way home (verify_after_loss)
  int round_ = 0;
  bool recalled_ = false;
  int home_round_ = 0;  // the round in which this agent went home
  bool loss_pending_ = false;
  double loss_since_s_ = 0.0;
  // Running, leader: an agent deep inside the line was lost during the pass. Its neighbours close
  // the gap while the flock holds (rewind_hold_), then the flock flies back to rewind_x_m_ (a
  // little before where the loss happened) and runs that stretch again with the line closed.
  bool rewind_hold_ = false;
  bool rewind_back_ = false;
  double rewind_x_m_ = 0.0;
  double rewind_since_s_ = 0.0;
  double all_landed_since_s_ = -1.0;  // landed, and every agent heard landed, since (flock_landed)
  bool verifying_ = false;
  double verify_since_s_ = 0.0;
  std::set<int> landed_ids_;  // agents heard to have landed: when they age out, nothing is lost
  // landed before a recall: the agents heard flying in the later round, and whether one of them
  // has been heard to land since (flock_landed)
  std::set<int> later_round_flyers_;
  bool later_round_over_ = false;

  // overlay network
  RadioPacer aggregate_pacer_;  // the aggregation frames, paced so that beacons go out on time
  uint16_t seq_ = 0;
  double next_beacon_s_ = 0.0;
  size_t record_cursor_ = 0;
  Eigen::Vector2d commanded_velocity_enu_m_s_ = Eigen::Vector2d::Zero();
  double target_heading_rad_ = 0.0;

  // the leader's work
  uint16_t query_counter_ = 0;
  int queries_started_ = 0;
  std::optional<AreaParts> gcs_map_;
  double gcs_map_at_s_ = -1e9;  // when the station's map last arrived
  std::optional<AreaParts> last_map_;
  std::optional<AreaParts>
      landed_map_;  // taken off again after a loss: what the landed agents held
  std::optional<PlannedPath> path_;
  double planned_fraction_ = 0.0;  // the map's covered fraction when path_ was planned

  std::array<double, kAgentStateCount> time_in_state_{};
};

}  // namespace uavsim::missions::coverage
