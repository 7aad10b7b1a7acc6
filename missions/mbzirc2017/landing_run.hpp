// One MBZIRC 2017 landing run in the simulator, as mbzirc2017-run does it: the server (the truck
// driven to the start, optionally at another speed), the UAV program on the lockstep, the
// launcher's own lockstep client (near misses from ground truth and the faults at every tick),
// and the score from ground truth. Its steps in the order main calls them.
#pragma once

#include <cstdint>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "near_miss.hpp"
#include "uavsim/launch/launcher.hpp"
#include "uavsim/launch/run_options.hpp"
#include "uavsim/vision/eight_track.hpp"

namespace uavsim::missions::mbzirc2017 {

// the options' limits (mbzirc2017-run --help), and the rules' truck speeds
inline constexpr double kMaxKmh = 60.0;
inline constexpr double kMaxStart_s = 3600.0;
inline constexpr double kMinRuleKmh = 5.0;  // the truck's speeds in the MBZIRC 2017 rules
inline constexpr double kMaxRuleKmh = 20.0;
inline constexpr int kMaxBlackouts = 20;
// random blackouts: from this long after the start to this long (the median landing is inside)
inline constexpr double kBlackoutFrom_s = 10.0;
inline constexpr double kBlackoutTo_s = 100.0;
inline constexpr double kBlackoutMin_s = 0.5;
inline constexpr double kBlackoutMax_s = 4.0;

struct LandingRunOptions : launch::RunOptions {
  double truck_speed_kmh = 0.0;  // 0: the world's (15 km/h)
  double start_time_s = 0.0;     // the UAV starts at this sim time (480: the 5 km/h phase)
  bool slow_phase = false;       // --phase slow
  // --start-phase: the fraction of a lap the truck drives before the start
  std::optional<double> start_phase;
  bool random_start_phase = false;  // --start-phase random
  bool random_truck_speed = false;  // --truck-speed-kmh random
  int random_blackouts = 0;
  bool no_record = false;  // --no-record: no video
  bool blackout_first_pass = false;
  bool lose_in_approach = false;
  bool lose_low_off_centre = false;
  double budget_s = 300.0;  // sim seconds after the UAV's start
  double wall_limit_s = 1200.0;
  std::string uav;
};

// The world's truck: its eight (uavsim:truck:track) and speed schedule (uavsim:truck:speed), with
// the defaults of server/src/objects/truck.hpp where the world says nothing.
struct TruckSchedule {
  vision::EightTrackParams track;
  double speed1_kmh = 15.0, speed2_kmh = 5.0, switch_s = 480.0;
};

// One run: the server and the UAV program on the lockstep, the launcher's own lockstep client
// (near misses and faults at every tick), the score from ground truth. Its steps in main's order.
class LandingRun {
 public:
  using Json = nlohmann::json;
  using Launcher = launch::Launcher;

  LandingRun(Launcher& launch, LandingRunOptions& o) : launch_(launch), o_(o) {}

  // the truck's schedule, where on the eight the UAV starts, the faults' times, the near-miss
  // shapes and the world file; 0, or the exit code after saying why
  int prepare();
  // instead of the mission (--floor): its floor (launch::run_floor), the UAV program's camera
  // rendered; the launcher's exit code
  int run_floor();
  // the server, on ephemeral ports
  void start_server();
  // the clock held at t = 0 (the truck alone driven to the start time), the UAV program and the
  // launcher on the lockstep, then the clock let go
  void set_up();
  // the program, the events and the ticks until the end
  void follow();
  // the clock held at the end, the events written, the score
  void finish();
  // the rewritten world removed (after the server has stopped)
  void clean_up() const;

  bool failed() const { return failed_; }
  bool success() const;
  void print_summary(bool success) const;
  Json summary_json(bool success) const;

 private:
  // the run's server: o_ with the world the truck's speed was written into
  launch::RunOptions server_options() const;
  void fail(const std::string& why) {
    std::fprintf(stderr, "mbzirc2017-run: %s\n", why.c_str());
    failed_ = true;
  }
  // the run's scored end: landed, and sim time t is 5 s after the touchdown (to a pause's slack)
  bool on_deck_long_enough(double t) const;
  void on_uav_line(const std::string& line);
  void on_sim_event(const Json& e);
  // the fault injector's tick: the near misses, then the faults due
  void on_tick(double tick_s);
  void track_near_miss(double tick_s);
  void inject_faults(double tick_s);
  void blackout(double tick_s, double duration_s, const std::string& why);
  // the wall-time status poll: the sim time, and the clock resumed towards the 5 s on the deck
  // (no_tick: this pass of the loop brought no tick, so the clock may be held)
  void poll_status(bool no_tick);
  // the loop's end, after a pass
  bool run_over();
  void score();
  double mission_s() const {
    return landed_s_ >= 0 && takeoff_s_ >= 0 ? landed_s_ - takeoff_s_ : -1.0;
  }
  double truck_kmh() const { return o_.slow_phase ? schedule_.speed2_kmh : schedule_.speed1_kmh; }

  Launcher& launch_;
  LandingRunOptions& o_;
  bool failed_ = false;
  TruckSchedule schedule_;
  std::optional<vision::EightTrack> track_;
  std::string world_;
  // the random blackouts: (time, duration), in time order
  std::vector<std::pair<double, double>> blackouts_;
  size_t next_blackout_ = 0;
  // the near misses, from the models the simulator collides
  std::optional<NearMissTracker> near_miss_;
  std::string part_at_approach_, part_at_touchdown_;  // where on the eight
  std::optional<double> approach_s_;                  // the first Approach's time (program output)
  double truck_s_m_ = 0.0;                            // the truck's arc length at the latest tick
  std::map<double, double> truck_s_by_tick_m_;  // ... and at the ticks of the last kTruckHistory_s
  double truck_yaw_rad_ = 0.0;                  // at the latest tick
  int climb_aways_ = 0;
  int estimate_steps_ = 0;  // the program's "position estimate stepped" (a GPS jump it noticed)
  // the ground truth the summary is scored from
  double takeoff_s_ = -1.0, landed_s_ = -1.0, relative_speed_m_s_ = -1.0;
  double marker_distance_m_ = -1.0;
  double end_sim_s_ = 0.0;
  bool stayed_on_deck_ = false;
  std::vector<std::string> crashes_, states_;
  std::string vision_log_;  // the UAV program's video log, in the run directory
  double first_blackout_s_ = -1.0, approach_blackout_s_ = -1.0;  // when the faults were injected
  double lose_low_at_s_ = -1.0;
  std::string uav_state_;  // the program's state, as of its output stamped before the latest tick
  double glitch_clear_s_ = -1.0;  // when --lose-low-off-centre's GPS offset ends (-1: none)
  std::vector<std::pair<std::int64_t, double>> ticks_;  // the fault injector's ticks (number, time)
  // the ground truth the server sent with the ticks (lockstep_join's with_tick: vehicles, truck),
  // by tick time, until the tick is handled
  std::map<double, Json> tick_truth_;
  std::vector<std::pair<double, std::string>>
      pending_states_;  // from the UAV's output, not yet acted on
  double sim_s_ = 0.0, last_status_wall_s_ = 0.0;
};

}  // namespace uavsim::missions::mbzirc2017
