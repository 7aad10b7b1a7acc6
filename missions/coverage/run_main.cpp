// coverage-run: the coverage flock (the thesis the project descends from, chapters 3 and 4) in the
// simulator: a generated world of N quads on a take-off line at the edge of a W x H rectangle,
// uavsim-server on it, the coverage-agent programs, all on the server's lockstep clock at full
// speed. It prints progress (coverage, leader, states), injects failures (every 10 s of sim time
// each flying agent fails with probability p: the sim API's kill_vehicle, drawn from the seed, at
// the launcher's own lockstep ticks so every run of a seed fails the same agents at the same
// times), and prints a summary scored from the sim API's ground truth, which the agents never
// see: the fraction of the rectangle covered by the data that survived (the APDs the agents still
// alive reported), mission time (first take-off to last touchdown), energy per agent, failed
// agents, distance flown, and the distance flown to recover lost data (recovery_meter.hpp: table
// 4.3's quantity). With --gcs (the optimised variant, section 3.6) it also starts the
// ground station (coverage-gcs) with a GCS link per vehicle through the server's relay, which can
// cut or impair them (--gcs-cut, --gcs-loss); data delivered to the station counts as surviving.
//
// The run ends at the first of the launcher's ticks (1 s) after every agent printed its end, or at
// the budget; the summary is scored there, so a seed's summary is the same every run (wall time and
// paths aside).
//
// SIGINT or SIGTERM stops the run cleanly: the agents, the station and the server are stopped and
// the summary so far is printed (JSON "interrupted": true, the interruption its "cause").
//
// Exit status: 0 only on full coverage with every surviving agent landed; 1: the mission fell
// short; 2: usage (or an unusable run directory); 4: the harness failed (the server died, named
// with how); 130: interrupted. An agent program that dies (a signal, a non-zero exit) is a failed
// agent: its quad is killed and the flock covers its area, as after an injected failure.
#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <limits>
#include <map>
#include <random>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include "agent.hpp"
#include "apd_report.hpp"
#include "coverage_config.hpp"
#include "coverage_world.hpp"
#include "recovery_meter.hpp"
#include "uavsim/client/sim_connection.hpp"
#include "uavsim/common/install_paths.hpp"
#include "uavsim/launch/launcher.hpp"

using namespace uavsim::missions::coverage;
using uavsim::client::Result;
using uavsim::client::SimConnection;
using uavsim::client::SimMessage;
using uavsim::launch::Launcher;
using Json = nlohmann::json;
using WallClock = std::chrono::steady_clock;

namespace {

constexpr double kLauncherTick_s = 1.0;    // the launcher's lockstep period (sampling, kills)
constexpr double kFailurePeriod_s = 10.0;  // failures are drawn every 10 s (thesis 4.3)
constexpr double kAgentPeriod_s = 0.05;    // the agents' lockstep period (20 Hz)
constexpr double kFullCoverage = 1.0 - 1e-3;
constexpr int kStationId = 255;

struct Options {
  int agents = 5;
  double length_x_m = 150.0, width_y_m = 100.0;
  double failure_prob = 0.0;
  uint64_t seed = 1;
  bool gcs = false;
  // the agents' one-tick compute latency (coverage-agent --pipelined); never with --gcs, whose UDP
  // links it would make timing-dependent
  bool pipelined = false;
  bool thesis_flocking = false;  // coverage-agent --thesis-flocking: Algorithm 3 as written
  double gcs_cut_s = -1.0;       // the GCS links cut (every datagram dropped) from this sim time on
  double gcs_loss = 0.0;         // each GCS-link datagram lost with this probability
  std::string json_path;
  bool quiet = false;
  double radio_range_m = 150.0;
  double line_spacing_m = WorldSpec{}.line_spacing_m;
  double radio_loss = 0.0;
  // the server's radio channel (--radio-backend): simple (closed form) or ns3 (ns-3's 802.15.4)
  std::string radio_backend = "simple";
  std::vector<std::pair<double, int>> kills;  // (sim time, agent)
  int per_process = 1;
  double budget_s = 3000.0;
  double wall_limit_s = 3600.0;
  double progress_period_s = 10.0;
  double agent_status_s = 0.0;
  // an install's own server and models (PREFIX/bin, PREFIX/share/uavsim/models), else the build's
  std::string server =
      uavsim::common::installed_or_built_program("uavsim-server", UAVSIM_SERVER_PATH);
  std::string agent;
  std::string gcs_program;
  std::string models_dir = uavsim::common::find_models_dir("", UAVSIM_MODELS_DIR).path;
  std::string keep_world;                  // write the generated world here too
  std::string run_dir = "auto";            // --run-dir: video, summary, events, logs, ground truth
  std::string record;                      // --record: the video (default video.mp4 in the run dir)
  bool no_record = false;                  // --no-record
  std::string record_camera = "overview";  // the server's --record-camera: the whole rectangle
  std::string map_png;  // --map: the coverage map (scripts/plot_run.py on the run directory)
  double truth_hz = 10.0;
};

int usage() {
  std::fprintf(stderr, R"(usage: coverage-run [options]
Runs the coverage flock (thesis ch. 3-4) in the simulator: server, agent programs, lockstep at full speed.
  --agents N          number of quads (1-64, default 5)
  --area WxH          rectangle: W along x (flight direction), H along y, metres (default 150x100)
  --failure-prob P    every 10 s of sim time each flying agent fails with probability P (0-1, seeded)
  --seed S            seed of the server (sensor noise, radio loss) and of the failures (default 1)
  --kill A@T          kill agent A at sim time T (repeatable; e.g. the leader: 0@60)
  --radio-range M     radio range (default 150 m)
  --line-spacing M    distance between neighbours on the take-off line (3-100, default 7 m)
  --radio-loss P      probability that a frame heard in range is lost (0-1, default 0; simple only)
  --radio-backend B   the radio channel: simple (default: closed form) or ns3 (ns-3's 802.15.4:
                      CSMA-CA, SINR; 116-byte frames, which the agents fit their messages to)
  --per-process K     agents per coverage-agent process (default 1)
  --budget S          sim-time limit (default 3000)
  --wall-limit S      wall-clock safety bound (default 3600)
  --progress S        progress line every S sim seconds (default 10)
  --agent-status S    each agent prints its pose and holdings every S sim seconds (default 0: no)
  --json FILE         write the summary as JSON
  --run-dir DIR       everything of the run in DIR (default auto: runs/coverage-seedN-TIME):
                      video.mp4, summary.json, events.jsonl and tlogs (the server's --log-dir),
                      truth_VEHICLE.csv (ground truth at --truth-hz, default 10);
                      scripts/plot_run.py DIR plots it
  --no-run-dir        no run directory (same as --run-dir none)
  --record FILE.mp4   video of the run (default video.mp4 in the run directory); --no-record: none
  --record-camera C   the video's view: overview (default: the whole rectangle from above),
                      follow (the flock), follow:VEHICLE, top
  --map FILE.png      the coverage map as a picture: covered once, by two or more agents, lost with
                      a dead agent, lost then covered again, delivered to the station, and the
                      tracks (scripts/plot_run.py on the run directory, which it needs)
  --world-out FILE    also write the generated world there
  --quiet             only the summary
  --gcs               the optimised variant (thesis 3.6): a ground station (coverage-gcs) that
                      receives the agents' data over their GCS links and sends its map back
  --gcs-cut T         cut every GCS link at sim time T (the server's relay drops all datagrams)
  --gcs-loss P        each GCS-link datagram is lost with probability P (0-1, seeded)
  --pipelined         the agents' outputs of a step go out at the next tick (a one-tick compute
                      latency) and the simulator steps while they think; default: zero latency, the
                      simulator waits for them at every tick. Not with --gcs
  --thesis-flocking   the flocking rules exactly as the thesis's Algorithm 3 (R1 alone wherever a
                      neighbour is within D_R1); default: where R1 pushes a follower towards the
                      leader, it also closes on the next agent that way, up to D_R1, at most 1 m/s
  --server/--agent/--gcs-program PATH, --models-dir DIR  programs and models (default: the build
                      tree)
)");
  return 2;
}

bool number(const char* s, double lo, double hi, double* out) {
  char* e = nullptr;
  const double v = std::strtod(s, &e);
  if (e == s || *e != '\0' || !std::isfinite(v) || v < lo || v > hi) return false;
  *out = v;
  return true;
}

std::string fmt(const char* f, double a) {
  char buf[64];
  std::snprintf(buf, sizeof buf, f, a);
  return buf;
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  o.agent = uavsim::launch::sibling_program("coverage-agent");
  o.gcs_program = uavsim::launch::sibling_program("coverage-gcs");
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    double v = 0, w = 0;
    if (a == "--quiet") {
      o.quiet = true;
      continue;
    }
    if (a == "--gcs") {
      o.gcs = true;
      continue;
    }
    if (a == "--pipelined") {
      o.pipelined = true;
      continue;
    }
    if (a == "--thesis-flocking") {
      o.thesis_flocking = true;
      continue;
    }
    if (a == "--no-record" || a == "--no-run-dir") {
      if (a == "--no-record") o.no_record = true;
      if (a == "--no-run-dir") o.run_dir = "none";
      continue;
    }
    if (a == "--help" || a == "-h" || i + 1 >= argc) return usage();
    const char* val = argv[++i];
    if (a == "--agents" && number(val, 1, kMaxAgents, &v) && v == std::floor(v)) {
      o.agents = static_cast<int>(v);
    } else if (a == "--area") {
      const char* x = std::strchr(val, 'x');
      if (x == nullptr || !number(std::string(val, x).c_str(), 10, 3000, &v) ||
          !number(x + 1, 10, 3000, &w))
        return usage();
      o.length_x_m = v;
      o.width_y_m = w;
    } else if (a == "--failure-prob" && number(val, 0, 1, &v)) {
      o.failure_prob = v;
    } else if (a == "--seed" && number(val, 0, 1e15, &v) && v == std::floor(v)) {
      o.seed = static_cast<uint64_t>(v);
    } else if (a == "--kill") {
      const char* at = std::strchr(val, '@');
      if (at == nullptr || !number(std::string(val, at).c_str(), 0, kMaxAgents - 1, &v) ||
          v != std::floor(v) || !number(at + 1, 0, 1e6, &w))
        return usage();
      o.kills.emplace_back(w, static_cast<int>(v));
    } else if (a == "--radio-range" && number(val, 1, 10000, &v)) {
      o.radio_range_m = v;
    } else if (a == "--line-spacing" && number(val, 3, 100, &v)) {
      o.line_spacing_m = v;
    } else if (a == "--radio-loss" && number(val, 0, 1, &v)) {
      o.radio_loss = v;
    } else if (a == "--radio-backend" &&
               (std::strcmp(val, "simple") == 0 || std::strcmp(val, "ns3") == 0)) {
      o.radio_backend = val;
    } else if (a == "--gcs-cut" && number(val, 0, 1e6, &v)) {
      o.gcs_cut_s = v;
    } else if (a == "--gcs-loss" && number(val, 0, 1, &v)) {
      o.gcs_loss = v;
    } else if (a == "--per-process" && number(val, 1, kMaxAgents, &v) && v == std::floor(v)) {
      o.per_process = static_cast<int>(v);
    } else if (a == "--budget" && number(val, 1, 1e6, &v)) {
      o.budget_s = v;
    } else if (a == "--wall-limit" && number(val, 1, 1e6, &v)) {
      o.wall_limit_s = v;
    } else if (a == "--progress" && number(val, 1, 1e6, &v)) {
      o.progress_period_s = v;
    } else if (a == "--agent-status" && number(val, 0, 3600, &v)) {
      o.agent_status_s = v;
    } else if (a == "--json") {
      o.json_path = val;
    } else if (a == "--run-dir") {
      o.run_dir = val;
    } else if (a == "--record") {
      o.record = val;
    } else if (a == "--record-camera") {
      o.record_camera = val;
    } else if (a == "--truth-hz" && number(val, 0.01, 1000, &v)) {
      o.truth_hz = v;
    } else if (a == "--map" && std::strchr(val, '\'') == nullptr) {
      o.map_png = val;
    } else if (a == "--world-out") {
      o.keep_world = val;
    } else if (a == "--server") {
      o.server = val;
    } else if (a == "--agent") {
      o.agent = val;
    } else if (a == "--gcs-program") {
      o.gcs_program = val;
    } else if (a == "--models-dir") {
      o.models_dir = val;
    } else {
      return usage();
    }
  }
  if (!o.gcs && (o.gcs_cut_s >= 0.0 || o.gcs_loss > 0.0)) {
    std::fprintf(stderr, "coverage-run: --gcs-cut and --gcs-loss need --gcs\n");
    return 2;
  }
  for (const auto& [t, id] : o.kills) {
    if (id >= o.agents) {
      std::fprintf(stderr, "coverage-run: --kill names agent %d of %d\n", id, o.agents);
      return 2;
    }
  }
  std::sort(o.kills.begin(), o.kills.end());
  if (const auto files = uavsim::launch::resolve_run_files("coverage", o.seed, o.run_dir, o.record,
                                                           o.json_path, !o.no_record);
      !files) {
    std::fprintf(stderr, "coverage-run: %s\n", files.message().c_str());
    return 2;
  } else {
    o.run_dir = files->dir;
    o.record = files->video;
    o.json_path = files->summary;
  }
  if (!o.map_png.empty() && o.run_dir.empty()) {
    std::fprintf(stderr, "coverage-run: --map needs a run directory (its ground truth)\n");
    return 2;
  }
  CoverageConfig config;
  config.length_x_m = o.length_x_m;
  config.width_y_m = o.width_y_m;
  WorldSpec spec;
  spec.agents = o.agents;
  spec.length_x_m = o.length_x_m;
  spec.width_y_m = o.width_y_m;
  spec.line_spacing_m = o.line_spacing_m;
  for (const std::string& why : {config.validate(), spec.validate()}) {
    if (!why.empty()) {
      std::fprintf(stderr, "coverage-run: %s\n", why.c_str());
      return 2;
    }
  }
  const int stripes = config.stripe_count();

  uavsim::launch::catch_interrupts();
  const auto wall_start = WallClock::now();
  auto wall_s = [&] {
    return std::chrono::duration<double>(WallClock::now() - wall_start).count();
  };
  auto say = [&](const std::string& s) {
    if (!o.quiet) {
      std::printf("%s\n", s.c_str());
      std::fflush(stdout);
    }
  };
  int harness_error = 0;
  auto fail = [&](const std::string& why) {
    std::fprintf(stderr, "coverage-run: %s\n", why.c_str());
    harness_error = 4;
  };

  // 1. the world, in a directory of its own
  std::string dir_template = (std::filesystem::temp_directory_path() / "coverage-run-XXXXXX");
  if (mkdtemp(dir_template.data()) == nullptr) {
    fail("cannot make a temporary directory");
    return 4;
  }
  const std::filesystem::path dir = dir_template;
  const std::string world_path = (dir / "coverage.xml").string();
  {
    std::ofstream(world_path) << coverage_world_xml(spec);
    if (!o.keep_world.empty()) std::ofstream(o.keep_world) << coverage_world_xml(spec);
  }

  // what the run learns
  std::map<int, std::string> state;  // agent -> its last state (from its output)
  std::map<int, int> leader_of;      // agent -> the leader it believes in
  std::map<int, ApdReport> apd;      // agent -> its last APD report
  std::set<int> leaders;             // agents that were ever in a leader state
  int completed_by = -1;             // the agent whose query found the rectangle covered
  int recalls = 0;                   // survey rounds restarted after a loss on the way home
  double completed_at_s = -1.0;      // and the sim time it found it (the going-home broadcast)
  // each agent's sim seconds in each state (fig. 4.9), summed over the agents in id order at the
  // end: floating-point sums in arrival order differ in the last bit from run to run
  std::map<int, std::array<double, kAgentStateCount>> agent_time_in_state_s;
  // agents that printed their end ("over: ..."): once all have, the run ends
  std::set<int> over;
  std::set<int> killed;              // agents killed (ground truth: vehicle_killed)
  std::set<int> crashed;             // crashes other than kills
  std::map<int, double> distance_m;  // horizontal distance flown (ground truth, 1 s samples)
  std::map<int, Eigen::Vector3d> last_pos;
  std::map<int, double> energy_mah;  // battery used, sampled at the launcher's ticks until disarmed
  std::map<int, bool> was_armed;
  double first_takeoff_s = -1, last_touchdown_s = -1, sim_s = 0;
  Json summary;
  std::vector<Json> vehicles_end;
  // the radio channel's counters at the end, summed over vehicles and links (radio_stats)
  Json radio_end = Json::object();
  std::vector<Json> gcs_links;
  std::map<int, int> station_port;  // vehicle -> the ground station's UDP port for its link
  RecoveryMeter recovery(stripes, config.width_y_m,
                         config.length_x_m);  // table 4.3's distance flown to recover
  // per failed agent: when, and the share of the rectangle that died with it
  std::map<int, std::pair<double, double>> failure_at;
  auto mark_failed = [&](int agent, std::set<int>& set, double t) {
    set.insert(agent);
    const double lost = recovery.agent_failed(agent);
    failure_at.try_emplace(agent, t, lost);
  };

  auto on_agent_line = [&](const std::string& line) {
    if (line.rfind("APD ", 0) == 0) {
      if (auto r = decode_apd_report(line, stripes)) {
        if (r->agent == kStationId) {
          recovery.station_report(r->apd);
        } else {
          recovery.agent_report(r->agent, r->apd);
        }
        apd[r->agent] = std::move(*r);
      }
      return false;  // not printed: long
    }
    static const std::regex state_re(R"(^agent (\d+) t=\S+ state (.+) leader (-?\d+)$)");
    static const std::regex complete_re(R"(^agent (\d+) t=(\S+) mission complete)");
    static const std::regex recall_re(R"(^agent \d+ t=\S+ .*\(recall: round \d+\))");
    static const std::regex times_re(R"(^agent (\d+) t=\S+ time in states:(.*)$)");
    static const std::regex over_re(R"(^agent (\d+) t=\S+ over: )");
    std::smatch m;
    if (std::regex_search(line, m, state_re)) {
      const int id = std::stoi(m[1]);
      state[id] = m[2];
      leader_of[id] = std::stoi(m[3]);
      if (m[2] == "Querying" || m[2] == "Deploying" || m[2] == "Running" || m[2] == "Waiting")
        leaders.insert(id);
    } else if (std::regex_search(line, m, complete_re)) {
      completed_by = std::stoi(m[1]);
      const double t = std::strtod(m[2].str().c_str(), nullptr);
      if (std::isfinite(t) && t >= 0.0) completed_at_s = t;
    } else if (std::regex_search(line, m, recall_re)) {
      ++recalls;
    } else if (std::regex_search(line, m, times_re)) {
      auto& times = agent_time_in_state_s[std::stoi(m[1])];
      times.fill(0.0);
      std::istringstream in(m[2].str());
      double v = 0.0;
      for (int k = 0; k < kAgentStateCount && in >> v; ++k) {
        if (std::isfinite(v) && v >= 0.0) times[static_cast<size_t>(k)] = v;
      }
    } else if (std::regex_search(line, m, over_re)) {
      over.insert(std::stoi(m[1]));
    }
    return true;
  };

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
  std::vector<Stamped> pending;
  std::uint64_t arrivals = 0;
  auto stamp = [&](double t_s, int source, std::function<void()> apply) {
    pending.push_back({t_s, source, arrivals++, std::move(apply)});
  };
  // applies what is stamped before t_s (everything: +infinity), in order
  auto apply_pending = [&](double t_s) {
    std::sort(pending.begin(), pending.end(), [](const Stamped& a, const Stamped& b) {
      return std::tie(a.t_s, a.source, a.arrival) < std::tie(b.t_s, b.source, b.arrival);
    });
    size_t n = 0;
    while (n < pending.size() && pending[n].t_s < t_s - 1e-9) ++n;
    std::vector<Stamped> due(std::make_move_iterator(pending.begin()),
                             std::make_move_iterator(pending.begin() + static_cast<long>(n)));
    pending.erase(pending.begin(), pending.begin() + static_cast<long>(n));
    for (Stamped& s : due) s.apply();
  };
  // a program's line: applied in order if it carries a sim time ("agent N t=T ...", an APD
  // report), at once otherwise (it is only printed)
  auto on_program_line = [&](const std::string& child, const std::string& line) {
    static const std::regex stamp_re(R"(^agent (\d+) t=(\S+) )");
    std::smatch m;
    int source = -1;
    double t_s = 0.0;
    if (line.rfind("APD ", 0) == 0) {
      if (auto r = decode_apd_report(line, stripes)) {
        source = r->agent;
        t_s = r->time_s;
      }
    } else if (std::regex_search(line, m, stamp_re)) {
      source = std::stoi(m[1]);
      t_s = std::strtod(m[2].str().c_str(), nullptr);
    }
    auto apply = [&, child, line] {
      if (on_agent_line(line)) say("[" + child + "] " + line);
    };
    if (source >= 0 && std::isfinite(t_s)) {
      stamp(t_s, source, apply);
    } else {
      apply();
    }
  };

  auto held_apd = [&] {
    AreaParts held(stripes);
    for (const auto& [id, r] : apd) {
      if (!killed.count(id) && !crashed.count(id)) held.merge(r.apd);
    }
    return held;
  };
  auto held_fraction = [&] { return held_apd().covered_fraction(config.width_y_m); };

  // 2. the server, on ephemeral ports, as fast as possible; the lines of every program go through
  // on_agent_line (the launcher's own printing is off: APD reports are not for people)
  Launcher launch("coverage-run", /*quiet=*/true);
  launch.keep_summary(o.json_path,
                      {{"mission", "coverage"}, {"seed", o.seed}, {"run_dir", o.run_dir}});
  std::map<std::string, std::pair<int, int>> agents_of;  // agent program -> its agents
  launch.on_exit([&](const uavsim::launch::ProgramEnd& e) {
    const auto it = agents_of.find(e.name);
    if (it == agents_of.end() || !e.abnormal()) return;
    for (int i = it->second.first; i <= it->second.second; ++i) {
      if (killed.count(i) || crashed.count(i)) continue;
      if (launch.api().request({{"op", "kill_vehicle"},
                                {"vehicle", i},
                                {"reason", "coverage-run: its agent program " + e.how}}))
        mark_failed(i, killed, sim_s);
    }
  });
  launch.on_line([&](const std::string& child, const std::string& line) {
    if (child == "server") {
      if (line.find(": MAVLink on tcp:") == std::string::npos) say("[server] " + line);
    } else {
      on_program_line(child, line);
    }
  });
  // cameras only for the video: the world's overview camera, which the agents never see
  std::vector<std::string> server_args{"--seed",     std::to_string(o.seed), "--models-dir",
                                       o.models_dir, "--radio-backend",      o.radio_backend};
  if (o.record.empty()) {
    server_args.push_back("--no-cameras");
  } else {
    server_args.insert(server_args.end(),
                       {"--record", o.record, "--record-camera", o.record_camera});
  }
  if (!o.run_dir.empty()) {
    server_args.insert(server_args.end(), {"--log-dir", o.run_dir});
    launch.record_truth(o.run_dir, o.truth_hz);
  }
  if (auto r = launch.start_server({o.server, world_path, server_args, 60.0}); !r) {
    fail("the server did not start: " + r.message());
  }

  std::mt19937_64 failure_rng(o.seed ^ 0x9e3779b97f4a7c15ULL);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  if (!harness_error) {
    SimConnection& api = launch.api();
    // 3. hold the clock at t = 0 with this seed; the radio; the events; the launcher's ticks
    Result<Json> r = api.pause();
    if (r) r = api.reset(o.seed);
    if (r)
      r = api.request({{"op", "radio_config"},
                       {"model", "range"},
                       {"range_m", o.radio_range_m},
                       {"loss", o.radio_loss}});
    if (r) r = api.subscribe_events();
    if (r) r = api.lockstep_join(kLauncherTick_s, 120.0);
    if (!r) fail("setting up the run: " + r.message());

    const std::string lockstep = launch.lockstep_env(kAgentPeriod_s);
    int processes = 0;
    // 4. the optimised variant: the ground station, its link ports, the server's relay in front
    // of each vehicle's link (seed 6.3), impaired as asked
    std::vector<int> gcs_uav_port(static_cast<size_t>(o.agents), 0);
    if (o.gcs) {
      static const std::regex port_re(R"(^gcs: uav(\d+) link on udp:[0-9.]+:(\d+)$)");
      launch.on_line([&](const std::string& child, const std::string& line) {
        std::smatch m;
        if (child == "gcs" && std::regex_search(line, m, port_re))
          station_port[std::stoi(m[1])] = std::stoi(m[2]);
      });
      if (auto g = launch.spawn("gcs",
                                {o.gcs_program, "--uavs", std::to_string(o.agents), "--area",
                                 fmt("%.3f", o.length_x_m) + "x" + fmt("%.3f", o.width_y_m)},
                                {lockstep});
          !g) {
        fail(g.message());
      }
      ++processes;
      while (!harness_error && static_cast<int>(station_port.size()) < o.agents &&
             launch.wall_s() < 60.0 && !launch.programs_done()) {
        launch.pump(100);
      }
      if (!harness_error && static_cast<int>(station_port.size()) < o.agents)
        fail("the ground station did not start");
      for (int i = 0; i < o.agents && !harness_error; ++i) {
        Result<Json> g = api.request({{"op", "gcs_link_open"},
                                      {"vehicle", i},
                                      {"gcs_target_host", "127.0.0.1"},
                                      {"gcs_target_port", station_port[i]}});
        if (g) gcs_uav_port[static_cast<size_t>(i)] = g->value("uav_port", 0);
        if (g && o.gcs_loss > 0.0)
          g = api.request({{"op", "gcs_link_impair"}, {"vehicle", i}, {"loss", o.gcs_loss}});
        if (!g) fail("GCS link of vehicle " + std::to_string(i) + ": " + g.message());
      }
    }
    // 5. the agent programs
    for (int first = 0; first < o.agents && !harness_error; first += o.per_process) {
      const int last = std::min(o.agents, first + o.per_process) - 1;
      std::string ports, gcs_ports;
      for (int i = first; i <= last; ++i) {
        const int port = launch.mavlink_port("uav" + std::to_string(i));
        if (port == 0) {
          fail("no MAVLink port for uav" + std::to_string(i));
          break;
        }
        ports += (ports.empty() ? "" : ",") + std::to_string(port);
        gcs_ports +=
            (gcs_ports.empty() ? "" : ",") + std::to_string(gcs_uav_port[static_cast<size_t>(i)]);
      }
      const std::string name = first == last
                                   ? "agent" + std::to_string(first)
                                   : "agents" + std::to_string(first) + "-" + std::to_string(last);
      std::vector<std::string> args{o.agent,
                                    "--vehicles",
                                    std::to_string(first) + "-" + std::to_string(last),
                                    "--area",
                                    fmt("%.3f", o.length_x_m) + "x" + fmt("%.3f", o.width_y_m),
                                    "--mavlink-ports",
                                    ports,
                                    "--status-period",
                                    fmt("%.3f", o.agent_status_s)};
      if (o.gcs) args.insert(args.end(), {"--gcs-ports", gcs_ports});
      if (o.pipelined && !o.gcs) args.push_back("--pipelined");
      if (o.thesis_flocking) args.push_back("--thesis-flocking");
      agents_of[name] = {first, last};
      if (auto s = launch.spawn(name, args, {lockstep}); !s) {
        fail(s.message());
      }
      ++processes;
    }
    // 6. once every program has joined the lockstep, let the clock go
    if (!harness_error) {
      if (auto w = launch.wait_lockstep_clients(processes + 1, 120.0); !w) {
        fail("the agent programs did not join the lockstep: " + w.message());
      } else if (!api.resume()) {
        fail("resume refused");
      } else {
        char buf[256];
        std::snprintf(buf, sizeof buf,
                      "coverage-run: %d agents, area %.0f x %.0f m (%d stripes), failure p %.4f, "
                      "radio %s range %.0f m loss %.2f, seed %llu%s",
                      o.agents, o.length_x_m, o.width_y_m, stripes, o.failure_prob,
                      o.radio_backend.c_str(), o.radio_range_m, o.radio_loss,
                      static_cast<unsigned long long>(o.seed),
                      o.gcs ? ", with a ground station" : "");
        say(buf);
      }
    }

    // 7. follow the run: the launcher's ticks (ground truth samples, kills), events, output
    size_t next_kill = 0;
    bool gcs_cut = false;
    double next_progress_s = o.progress_period_s;
    // the end of the run: the first of the launcher's ticks after every agent printed its end (or
    // the one at the budget). The ground truth is scored there, the clock held, so the summary
    // does not depend on when the programs' exits are noticed; the launcher then leaves the
    // lockstep and reads the programs' last lines until they exit.
    bool ended = false;
    auto end_at_tick = [&]() {
      if (auto v = api.request({{"op", "vehicles"}})) {
        sim_s = v->value("time_s", sim_s);
        for (const Json& x : (*v)["vehicles"]) vehicles_end.push_back(x);
      }
      // what the radio channel did: frames sent, refused, delivered, lost
      if (auto r = api.request({{"op", "radio_stats"}})) {
        Json totals = {{"backend", r->value("backend", "")},
                       {"max_frame_bytes", r->value("max_frame_bytes", 0)}};
        auto sum = [&totals](const Json& rows, std::initializer_list<const char*> fields) {
          for (const char* f : fields) {
            uint64_t n = 0;
            for (const Json& row : rows) n += row.value(f, uint64_t{0});
            totals[f] = n;
          }
        };
        sum((*r)["vehicles"], {"transmitted", "refused", "channel_access_failures"});
        sum((*r)["links"], {"sent", "delivered", "lost", "collided", "out_of_range", "no_ack"});
        radio_end = std::move(totals);
      }
      // what the relay did to each GCS link
      for (int i = 0; o.gcs && i < o.agents; ++i) {
        if (auto g = api.request({{"op", "gcs_link_stats"}, {"vehicle", i}}))
          gcs_links.push_back(*g);
      }
      (void)api.lockstep_leave();
      ended = true;
    };
    while (!harness_error) {
      launch.pump(50);
      for (const SimMessage& msg : api.take_messages()) {
        const Json& e = msg.json;
        const std::string ev = msg.kind();
        if (ev == "sim_event") {
          const std::string type = e.value("type", "");
          const double t = e.value("time", 0.0);
          const int veh = e.value("vehicle", -1);
          stamp(t, -1,
                [&, type, t, veh, name = e.value("vehicle_name", ""),
                 detail = e.value("detail", "")] {
                  if (type == "takeoff")
                    first_takeoff_s = first_takeoff_s < 0 ? t : std::min(first_takeoff_s, t);
                  if (type == "touchdown" && !killed.count(veh))
                    last_touchdown_s = std::max(last_touchdown_s, t);
                  if (type == "vehicle_killed") mark_failed(veh, killed, t);
                  if (type == "crash" && !killed.count(veh)) mark_failed(veh, crashed, t);
                  if (type == "crash" || type == "vehicle_killed")
                    say("[event] t=" + fmt("%.2f", t) + " " + type + " " + name + " " + detail);
                });
        } else if (ev == "tick" && !ended) {
          const double t = e.value("time", 0.0);
          sim_s = t;
          // what the programs printed before this tick has arrived: read it, apply it in order
          launch.pump(0);
          apply_pending(t);
          launch.note_sim_time(t);
          // ground truth: distance flown, energy, who is flying
          std::vector<int> flying;
          if (auto v = api.request({{"op", "vehicles"}})) {
            for (const Json& x : (*v)["vehicles"]) {
              const int i = x.value("index", -1);
              const Json p = x["position_enu_m"];
              const Eigen::Vector3d pos(p[0].get<double>(), p[1].get<double>(), p[2].get<double>());
              if (last_pos.count(i)) distance_m[i] += (pos - last_pos[i]).head<2>().norm();
              last_pos[i] = pos;
              // energy up to the disarm (a landed quad's boards would be switched off)
              const bool armed = x.value("armed", false);
              if (armed || !was_armed[i]) energy_mah[i] = x.value("battery_used_mah", 0.0);
              was_armed[i] = was_armed[i] || armed;
              if (armed && !x.value("crashed", false) && !x.value("on_ground", true))
                flying.push_back(i);
            }
          }
          // failures: scheduled kills, then every 10 s a draw per flying agent
          std::vector<int> to_kill;
          while (next_kill < o.kills.size() && o.kills[next_kill].first <= t + 1e-9)
            to_kill.push_back(o.kills[next_kill++].second);
          const long k = std::lround(t / kFailurePeriod_s);
          if (o.failure_prob > 0 && k > 0 && std::abs(t - k * kFailurePeriod_s) < 1e-6) {
            for (int i : flying) {
              if (uniform(failure_rng) < o.failure_prob) to_kill.push_back(i);
            }
          }
          // the ground station's links cut: every datagram dropped from now on
          if (o.gcs && !gcs_cut && o.gcs_cut_s >= 0.0 && t + 1e-9 >= o.gcs_cut_s) {
            gcs_cut = true;
            for (int i = 0; i < o.agents; ++i) {
              if (!api.request({{"op", "gcs_link_impair"}, {"vehicle", i}, {"outage_s", 1e6}}))
                fail("cutting the GCS link of vehicle " + std::to_string(i));
            }
            say("coverage-run: t=" + fmt("%.1f", t) + " GCS links cut");
          }
          for (int i : to_kill) {
            if (killed.count(i)) continue;
            if (api.request({{"op", "kill_vehicle"},
                             {"vehicle", i},
                             {"reason", "coverage-run: injected failure"}})) {
              mark_failed(i, killed, t);
              say("coverage-run: t=" + fmt("%.1f", t) + " killed agent " + std::to_string(i));
            }
          }
          // the video's coverage counter: what the surviving agents' reports hold, as scored
          if (!o.record.empty()) {
            (void)api.request(
                {{"op", "overlay_counter"},
                 {"name", "coverage"},
                 {"text", "coverage " + fmt("%.1f", 100.0 * held_fraction()) + " %"}});
          }
          if (t + 1e-9 >= next_progress_s) {
            next_progress_s += o.progress_period_s;
            std::map<std::string, int> counts;
            int leader = -1;
            for (const auto& [id, s] : state) {
              if (killed.count(id)) continue;
              ++counts[s];
              if (s == "Querying" || s == "Deploying" || s == "Running" || s == "Waiting")
                leader = leader < 0 ? id : std::min(leader, id);
            }
            std::string line = "coverage-run: t=" + fmt("%.0f", t) + " s coverage " +
                               fmt("%.1f", 100.0 * held_fraction()) + " % leader " +
                               (leader < 0 ? std::string("-") : std::to_string(leader)) + " |";
            for (const auto& [s, n] : counts) line += " " + s + " " + std::to_string(n);
            line += " | wall " + fmt("%.1f", wall_s()) + " s";
            say(line);
          }
          if (static_cast<int>(over.size()) >= o.agents || t + 1e-9 >= o.budget_s) {
            end_at_tick();
            continue;
          }
          if (!api.done(e.value("tick", std::int64_t{0}))) fail("the launcher's done was refused");
        }
      }
      // the server first: its death ends the agents too, and that is the harness's failure
      if (launch.server_exited() || !api.connected()) {
        fail(launch.server_end());
        break;
      }
      if (launch.programs_done(o.gcs ? "gcs" : "")) break;
      if (uavsim::launch::interrupted()) break;
      if (!launch.records_error().empty()) {
        fail("the run's records cannot be written: " + launch.records_error());
        break;
      }
      if (ended && sim_s + 1e-9 >= o.budget_s) {
        say("coverage-run: sim-time budget spent");
        break;
      }
      if (wall_s() > o.wall_limit_s) {
        say("coverage-run: wall-clock limit reached");
        break;
      }
    }

    // 8. score from ground truth, where the run did not reach its end (the programs gone before
    // it, interrupted, the wall-clock limit): as the clock stands
    if (!harness_error && !ended) end_at_tick();
  }

  // 9. stop everything we started (the ground station prints its last map as it stops)
  launch.stop_all(30.0);
  std::filesystem::remove_all(dir);
  apply_pending(std::numeric_limits<double>::infinity());  // the programs' last lines
  std::array<double, kAgentStateCount> time_in_state_s{};  // summed over agents (fig. 4.9)
  for (const auto& [id, times] : agent_time_in_state_s) {
    for (size_t k = 0; k < times.size(); ++k) time_in_state_s[k] += times[k];
  }

  const double coverage = held_fraction();
  int survivors = 0, landed = 0;
  double energy_total = 0, distance_total = 0;
  Json per_agent = Json::array();
  for (const Json& x : vehicles_end) {
    const int i = x.value("index", -1);
    const bool dead = killed.count(i) || crashed.count(i) || x.value("crashed", false);
    const bool down = x.value("on_ground", false) && !x.value("armed", true);
    if (!dead) {
      ++survivors;
      if (down) ++landed;
    }
    const double mah = energy_mah[i];
    energy_total += mah;
    distance_total += distance_m[i];
    Json entry = {
        {"agent", i},
        {"failed", dead},
        {"landed", down && !dead},
        {"state", state.count(i) ? state[i] : ""},
        {"energy_mah", mah},
        {"held_fraction", apd.count(i) ? apd[i].apd.covered_fraction(config.width_y_m) : 0.0},
        {"distance_m", distance_m[i]}};
    if (auto f = failure_at.find(i); f != failure_at.end()) {
      entry["failed_at_s"] = f->second.first;
      entry["lost_fraction"] = f->second.second;
    }
    per_agent.push_back(std::move(entry));
  }
  const bool success = harness_error == 0 && !uavsim::launch::interrupted() &&
                       !vehicles_end.empty() && coverage >= kFullCoverage && survivors > 0 &&
                       landed == survivors;
  const double mission_s = first_takeoff_s >= 0 && last_touchdown_s >= first_takeoff_s
                               ? last_touchdown_s - first_takeoff_s
                               : -1.0;
  // the thesis's fig. 4.7 and table 4.2 count "from take-off to landing" (mission_s); the time to
  // coverage ends where the leader's query found the rectangle covered, before the flight home
  const double coverage_s = first_takeoff_s >= 0 && completed_at_s >= first_takeoff_s
                                ? completed_at_s - first_takeoff_s
                                : -1.0;
  const int failed = static_cast<int>(vehicles_end.size()) - survivors;
  std::printf("==== coverage flock: %d agents, %.0f x %.0f m, failure p %.4f, seed %llu ====\n",
              o.agents, o.length_x_m, o.width_y_m, o.failure_prob,
              static_cast<unsigned long long>(o.seed));
  std::printf("coverage held by surviving agents%s: %.2f %%\n",
              o.gcs ? " and the ground station" : "", 100.0 * coverage);
  const double gcs_fraction =
      apd.count(kStationId) ? apd[kStationId].apd.covered_fraction(config.width_y_m) : 0.0;
  if (o.gcs) std::printf("ground station holds: %.2f %%\n", 100.0 * gcs_fraction);
  if (mission_s >= 0)
    std::printf("mission time: %.1f s sim (first take-off %.1f s, last touchdown %.1f s)\n",
                mission_s, first_takeoff_s, last_touchdown_s);
  else
    std::printf("mission time: n/a\n");
  if (coverage_s >= 0)
    std::printf(
        "coverage complete: %.1f s after the first take-off (the leader's query at %.1f s); "
        "going home and landing: %.1f s\n",
        coverage_s, completed_at_s, mission_s >= 0 ? mission_s - coverage_s : 0.0);
  std::printf("failed agents: %d of %d", failed, static_cast<int>(vehicles_end.size()));
  for (int i : killed) std::printf(" %d", i);
  for (int i : crashed) std::printf(" %d(crash)", i);
  std::printf("\nlanded: %d of %d surviving\n", landed, survivors);
  // what the surviving data misses: (stripe, y from, y to), the first few
  Json gaps = Json::array();
  {
    const AreaParts held = held_apd();
    for (int st = 0; st < stripes; ++st) {
      double y = 0.0;
      std::vector<Interval> list = held.stripe(st);
      list.push_back({config.width_y_m, config.width_y_m});
      for (const Interval& iv : list) {
        if (iv.start_m - y > kCoverageSlack_m && gaps.size() < 20)
          gaps.push_back({st, y, std::min(iv.start_m, config.width_y_m)});
        y = std::max(y, iv.end_m);
      }
    }
  }
  if (!gaps.empty()) std::printf("gaps (stripe, y from, y to): %s\n", gaps.dump().c_str());
  std::printf("leaders: ");
  for (int i : leaders) std::printf("%d ", i);
  std::printf("(completed by %d)", completed_by);
  if (recalls > 0) std::printf(", %d recall(s) after losses on the way home", recalls);
  std::printf("\n");
  {
    // fig. 4.9: share of the agents' time in each state, Going Home, Landed and Failed left out
    double total = 0.0;
    for (int k = 0; k < kAgentStateCount; ++k) {
      const auto st = static_cast<AgentState>(k);
      if (st != AgentState::kGoingHome && st != AgentState::kLanded && st != AgentState::kFailed)
        total += time_in_state_s[static_cast<size_t>(k)];
    }
    if (total > 0.0) {
      std::printf("time in states (fig. 4.9):");
      for (int k = 0; k < kAgentStateCount; ++k) {
        const auto st = static_cast<AgentState>(k);
        if (st == AgentState::kGoingHome || st == AgentState::kLanded || st == AgentState::kFailed)
          continue;
        std::printf(" %s %.1f %%", agent_state_name(st),
                    100.0 * time_in_state_s[static_cast<size_t>(k)] / total);
      }
      std::printf("\n");
    }
  }
  if (!vehicles_end.empty()) {
    std::printf("energy: %.0f mAh per agent (mean), %.0f mAh in all\n",
                energy_total / vehicles_end.size(), energy_total);
    std::printf("distance flown: %.0f m in all, %.0f m per agent (mean)\n", distance_total,
                distance_total / vehicles_end.size());
    if (failed > 0) {
      std::printf(
          "distance flown to recover lost data (table 4.3): %.0f m, %.3f %% of the distance "
          "flown; %.2f %% of the rectangle photographed again after it was lost, %.2f %% lost "
          "at the failures\n",
          recovery.distance_m(),
          distance_total > 0 ? 100.0 * recovery.distance_m() / distance_total : 0.0,
          100.0 * recovery.recovered_fraction(), 100.0 * recovery.lost_at_failures_fraction());
    }
  }
  if (radio_end.contains("transmitted")) {
    std::printf(
        "radio (%s, frames of at most %d bytes): %llu frames sent, %llu refused, %llu "
        "channel-access "
        "failures; %llu delivered, %llu lost\n",
        radio_end["backend"].get<std::string>().c_str(), radio_end["max_frame_bytes"].get<int>(),
        static_cast<unsigned long long>(radio_end["transmitted"].get<uint64_t>()),
        static_cast<unsigned long long>(radio_end["refused"].get<uint64_t>()),
        static_cast<unsigned long long>(radio_end["channel_access_failures"].get<uint64_t>()),
        static_cast<unsigned long long>(radio_end["delivered"].get<uint64_t>()),
        static_cast<unsigned long long>(radio_end["lost"].get<uint64_t>()));
  }
  std::printf("sim time: %.1f s, wall time: %.1f s, speed %.1fx real time\n", sim_s, wall_s(),
              wall_s() > 0 ? sim_s / wall_s() : 0.0);
  std::printf("video: %s\n", o.record.empty() ? "none" : o.record.c_str());
  if (!o.run_dir.empty()) {
    std::printf("run directory: %s (%llu ground-truth rows; plots: scripts/plot_run.py %s)\n",
                o.run_dir.c_str(), static_cast<unsigned long long>(launch.truth_rows()),
                o.run_dir.c_str());
  }
  std::printf("RESULT: %s coverage=%.4f mission_s=%.1f coverage_s=%.1f failed=%d landed=%d/%d%s\n",
              success ? "SUCCESS" : "FAILURE", coverage, mission_s, coverage_s, failed, landed,
              survivors, uavsim::launch::interrupted() ? " (interrupted)" : "");
  std::fflush(stdout);

  if (!o.json_path.empty()) {
    summary["mission"] = "coverage";
    summary["run_dir"] = o.run_dir;
    summary["video"] = o.record;
    summary["area_origin_m"] = {0.0, 0.0};
    summary["agents"] = o.agents;
    summary["area_m"] = {o.length_x_m, o.width_y_m};
    summary["failure_prob"] = o.failure_prob;
    summary["radio_range_m"] = o.radio_range_m;
    summary["radio_loss"] = o.radio_loss;
    summary["radio_backend"] = o.radio_backend;
    summary["radio"] = radio_end;
    summary["line_spacing_m"] = o.line_spacing_m;
    summary["thesis_flocking"] = o.thesis_flocking;
    summary["gcs"] = o.gcs;
    if (o.gcs) {
      summary["gcs_cut_s"] = o.gcs_cut_s;
      summary["gcs_loss"] = o.gcs_loss;
      summary["gcs_held_fraction"] = gcs_fraction;
      summary["gcs_links"] = gcs_links;
    }
    summary["seed"] = o.seed;
    summary["coverage"] = coverage;
    summary["mission_time_s"] = mission_s;
    summary["first_takeoff_s"] = first_takeoff_s;
    summary["last_touchdown_s"] = last_touchdown_s;
    summary["coverage_complete_s"] = coverage_s;
    summary["completed_at_s"] = completed_at_s;
    summary["failed"] = failed;
    summary["killed"] = std::vector<int>(killed.begin(), killed.end());
    summary["crashed"] = std::vector<int>(crashed.begin(), crashed.end());
    summary["survivors"] = survivors;
    summary["gaps"] = gaps;
    Json states = Json::object();
    for (int k = 0; k < kAgentStateCount; ++k)
      states[agent_state_name(static_cast<AgentState>(k))] =
          time_in_state_s[static_cast<size_t>(k)];
    summary["time_in_state_s"] = states;
    summary["leaders"] = std::vector<int>(leaders.begin(), leaders.end());
    summary["completed_by"] = completed_by;
    summary["recalls"] = recalls;
    summary["landed"] = landed;
    summary["energy_mah_mean"] = vehicles_end.empty() ? 0.0 : energy_total / vehicles_end.size();
    summary["distance_m_total"] = distance_total;
    summary["recovery_distance_m"] = recovery.distance_m();
    summary["recovered_fraction"] = recovery.recovered_fraction();
    summary["lost_fraction_at_end"] = recovery.lost_fraction();
    summary["lost_at_failures_fraction"] = recovery.lost_at_failures_fraction();
    summary["per_agent"] = per_agent;
    // every agent's last APD report, the dead's and the station's (255) too: the coverage map
    summary["stripes"] = stripes;
    Json apds = Json::array();
    for (const auto& [id, r] : apd) {
      apds.push_back({{"agent", id},
                      {"failed", killed.count(id) > 0 || crashed.count(id) > 0},
                      {"report", encode_apd_report(id, r.time_s, r.apd)}});
    }
    summary["apd_reports"] = apds;
    summary["sim_time_s"] = sim_s;
    summary["wall_time_s"] = wall_s();
    summary["success"] = success;
    if (!launch.write_summary(o.json_path, summary)) harness_error = 4;
    const std::string run_summary = o.run_dir + "/summary.json";
    if (!o.map_png.empty() && o.json_path != run_summary &&
        !launch.write_summary(run_summary, summary))  // what plot_run.py reads
      harness_error = 4;
  }
  if (!o.map_png.empty() && !o.json_path.empty() && o.run_dir.find('\'') == std::string::npos) {
    // the picture from the run directory (ground truth, summary); matplotlib's script
    const std::string plot = uavsim::common::installed_or_built_program(
        "uavsim-plot", std::string(UAVSIM_SCRIPTS_DIR) + "/plot_run.py");
    const std::string cmd = "'" + plot + "' '" + o.run_dir + "' --coverage-map '" + o.map_png + "'";
    if (std::system(cmd.c_str()) != 0)
      std::fprintf(stderr, "coverage-run: the coverage map was not drawn (%s)\n", cmd.c_str());
  }
  return uavsim::launch::run_exit_code(harness_error != 0, success);
}
