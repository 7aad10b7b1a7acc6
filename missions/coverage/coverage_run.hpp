// One run of the coverage flock in the simulator, as coverage-run does it: the generated world,
// the server, the agent programs (and the ground station) on the lockstep, the launcher's own
// ticks (ground-truth samples, injected failures), and the score from ground truth and the
// agents' last reports. Its steps in the order main calls them.
#pragma once

#include <Eigen/Core>
#include <array>
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <random>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "agent.hpp"
#include "apd_report.hpp"
#include "coverage_config.hpp"
#include "coverage_world.hpp"
#include "recovery_meter.hpp"
#include "run_options.hpp"
#include "run_score.hpp"
#include "uavsim/launch/launcher.hpp"

namespace uavsim::missions::coverage {

// The score at the end, from ground truth and the programs' last reports.
// The counts, totals, times and success are the pure tally of run_score.hpp.
struct CoverageScore : RunTally {
  using Json = nlohmann::json;

  Json per_agent = Json::array();
  double gcs_fraction = 0.0;
  // what the surviving data misses: (stripe, y from, y to), the first few
  Json gaps = Json::array();
  std::array<double, kAgentStateCount> time_in_state_s{};  // summed over agents (fig. 4.9)
};

// One run of the flock: the world, the server, the programs on the lockstep, the launcher's own
// ticks (ground truth samples, failures), the score. Its steps in main's order.
class CoverageRun {
 public:
  using Json = nlohmann::json;
  using Launcher = launch::Launcher;

  CoverageRun(const CoverageRunOptions& o, const CoverageConfig& config, const WorldSpec& spec);

  // 1. the world, in a directory of its own; false after saying why
  bool make_world();
  // 2. the server, with every program's lines and ends followed
  void start(Launcher& launch);
  // instead of 2.-8. (--floor): the run's floor (launch::run_floor) on the world of 1.; the
  // launcher's exit code
  int run_floor(Launcher& launch);
  // 3.-6. the clock held at t = 0, the radio, the programs, then the clock let go
  void set_up();
  // 7.-8. the run followed to its end, scored there
  void follow();
  // 9. after the programs stopped: their last lines, the temporary world gone; the score
  CoverageScore finish();
  void print_summary(const CoverageScore& s);
  Json summary_json(const CoverageScore& s);
  // the coverage map as a picture (--map), from the run directory
  void draw_map() const;
  bool failed() const { return failed_; }

 private:
  // the run's server: the options with the world of 1., and the mission's own arguments
  launch::RunOptions server_options() const;
  std::vector<std::string> server_args() const;
  double wall_s() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start_).count();
  }
  void say(const std::string& s) const {
    if (!o_.quiet) {
      std::printf("%s\n", s.c_str());
      std::fflush(stdout);
    }
  }
  void fail(const std::string& why) {
    std::fprintf(stderr, "coverage-run: %s\n", why.c_str());
    failed_ = true;
  }
  void mark_failed(int agent, std::set<int>& set, double t) {
    set.insert(agent);
    const double lost = recovery_.agent_failed(agent);
    failure_at_.try_emplace(agent, t, lost);
  }
  bool on_agent_line(const std::string& line);
  void stamp(double t_s, int source, std::function<void()> apply) {
    pending_.push_back({t_s, source, arrivals_++, std::move(apply)});
  }
  void apply_pending(double t_s);
  void on_program_line(const std::string& child, const std::string& line);
  AreaParts held_apd() const;
  double held_fraction() const { return held_apd().covered_fraction(config_.width_y_m); }
  void start_ground_station(const std::string& lockstep);
  void start_agents(const std::string& lockstep);
  void on_sim_event(const Json& e);
  void on_tick(const Json& e);
  // ground truth at a tick: distance flown, energy; the agents flying
  std::vector<int> sample_truth();
  void inject_failures(double t, const std::vector<int>& flying);
  void print_progress(double t);
  // the run's end at a tick: the ground truth scored there, the lockstep left
  void end_at_tick();
  bool run_over();
  Json gaps() const;
  void print_time_in_states(const std::array<double, kAgentStateCount>& time_in_state_s) const;
  void print_radio() const;
  // the radio_config send_spread_s of this run (--radio-send-spread, or its default)
  double send_spread_s() const;

  const CoverageRunOptions& o_;
  CoverageConfig config_;
  WorldSpec spec_;
  int stripes_;
  std::chrono::steady_clock::time_point wall_start_;
  Launcher* launch_ = nullptr;
  bool failed_ = false;
  std::filesystem::path dir_;
  std::string world_path_;

  // what the run learns
  std::map<int, std::string> state_;  // agent -> its last state (from its output)
  std::map<int, int> leader_of_;      // agent -> the leader it believes in
  std::map<int, ApdReport> apd_;      // agent -> its last APD report
  std::set<int> leaders_;             // agents that were ever in a leader state
  int completed_by_ = -1;             // the agent whose query found the rectangle covered
  int recalls_ = 0;                   // survey rounds restarted after a loss on the way home
  double completed_at_s_ = -1.0;      // and the sim time it found it (the going-home broadcast)
  // each agent's sim seconds in each state (fig. 4.9), summed over the agents in id order at the
  // end: floating-point sums in arrival order differ in the last bit from run to run
  std::map<int, std::array<double, kAgentStateCount>> agent_time_in_state_s_;
  // agents that printed their end ("over: ..."): once all have, the run ends
  std::set<int> over_;
  std::set<int> killed_;              // agents killed (ground truth: vehicle_killed)
  std::set<int> crashed_;             // crashes other than kills
  std::map<int, double> distance_m_;  // horizontal distance flown (ground truth, 1 s samples)
  std::map<int, Eigen::Vector3d> last_pos_;
  std::map<int, double>
      energy_mah_;  // battery used, sampled at the launcher's ticks until disarmed
  std::map<int, bool> was_armed_;
  double first_takeoff_s_ = -1, last_touchdown_s_ = -1, sim_s_ = 0;
  std::vector<Json> vehicles_end_;
  // the radio channel's counters at the end, summed over vehicles and links (radio_stats)
  Json radio_end_ = Json::object();
  std::vector<Json> gcs_links_;
  std::map<int, int> station_port_;  // vehicle -> the ground station's UDP port for its link
  RecoveryMeter recovery_;           // table 4.3's distance flown to recover
  // per failed agent: when, and the share of the rectangle that died with it
  std::map<int, std::pair<double, double>> failure_at_;
  std::map<std::string, std::pair<int, int>> agents_of_;  // agent program -> its agents

  // The programs' lines and the server's events reach the launcher in an order that depends on
  // wall-clock timing (one pipe per program, the API's socket); they are applied in sim-time order
  // instead: by stamp, then events before lines, then the agent's id, then arrival. At each of the
  // launcher's ticks, whatever is stamped before it is applied: by then all of it has arrived (a
  // program prints before it reports its tick done, and the server sends an event before the next
  // tick). So a seed's run scores the same every time, failures and recoveries included.
  struct Stamped {
    double t_s;
    int source;  // -1: an event; otherwise the agent's id (the station's: 255)
    std::uint64_t arrival;
    std::function<void()> apply;
  };
  std::vector<Stamped> pending_;
  std::uint64_t arrivals_ = 0;

  // the failures and the run's course
  std::mt19937_64 failure_rng_;
  std::uniform_real_distribution<double> uniform_{0.0, 1.0};
  int processes_ = 0;
  std::vector<int> gcs_uav_port_;
  size_t next_kill_ = 0;
  bool gcs_cut_ = false;
  double next_progress_s_ = 0.0;
  // the end of the run: the first of the launcher's ticks after every agent printed its end (or
  // the one at the budget). The ground truth is scored there, the clock held, so the summary
  // does not depend on when the programs' exits are noticed; the launcher then leaves the
  // lockstep and reads the programs' last lines until they exit.
  bool ended_ = false;
};

}  // namespace uavsim::missions::coverage
