// coverage-run's options: the launchers' common ones (uavsim/launch/run_options.hpp) and the
// flock's, from its command line.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "coverage_world.hpp"
#include "uavsim/launch/run_options.hpp"

namespace uavsim::missions::coverage {

struct CoverageRunOptions : launch::RunOptions {
  CoverageRunOptions();  // the defaults: the build's or an install's server, the overview camera
  int agents = 5;
  double length_x_m = 150.0, width_y_m = 100.0;
  double failure_prob = 0.0;
  bool gcs = false;
  // the agents' one-tick compute latency (coverage-agent --pipelined); never with --gcs, whose UDP
  // links it would make timing-dependent
  bool pipelined = false;
  bool thesis_flocking = false;  // coverage-agent --thesis-flocking: Algorithm 3 as written
  double gcs_cut_s = -1.0;       // the GCS links cut (every datagram dropped) from this sim time on
  double gcs_loss = 0.0;         // each GCS-link datagram lost with this probability
  double radio_range_m = 150.0;
  double line_spacing_m = WorldSpec{}.line_spacing_m;
  double radio_loss = 0.0;
  // the server's radio channel (--radio-backend): simple (closed form) or ns3 (ns-3's 802.15.4)
  std::string radio_backend = "simple";
  // --radio-technology: ns3's 802.15.4 (lr-wpan, the default) or 802.11g ad hoc at 6 Mbit/s
  std::string radio_technology = "802.15.4";
  // --radio-send-spread S: on ns3, frames enter the channel at seeded offsets up to S after they
  // were sent (the server's send_spread_s; 0: one step on 802.11, none on 802.15.4). Default
  // (negative): the agents' tick on 802.11, whose real programs run on clocks of their own (in
  // lockstep they all send at the tick, and DCF starts such frames together); none on 802.15.4
  double radio_send_spread_s = -1.0;
  // --radio-tdma D: the seed's TDMA with slots of D seconds in a 1 s period (the GPS pulse); 0: off
  double radio_tdma_slot_s = 0.0;
  std::vector<std::pair<double, int>> kills;  // (sim time, agent)
  int per_process = 1;
  double budget_s = 3000.0;
  double wall_limit_s = 3600.0;
  double progress_period_s = 10.0;
  double agent_status_s = 0.0;
  std::string agent;
  std::string gcs_program;
  // an install's own models (PREFIX/share/uavsim/models), else the build's
  std::string models_dir;
  std::string keep_world;  // write the generated world here too
  bool no_record = false;  // --no-record
  std::string map_png;     // --map: the coverage map (scripts/plot_run.py on the run directory)
};

// The command line into o; false when it is not usable (usage).
bool parse_run_options(int argc, char** argv, CoverageRunOptions* o);
// The checks between the options; false after saying why on stderr.
bool run_options_agree(const CoverageRunOptions& o);

}  // namespace uavsim::missions::coverage
