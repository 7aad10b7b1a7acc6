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
#include <algorithm>
#include <cstdio>
#include <string>

#include "coverage_config.hpp"
#include "coverage_run.hpp"
#include "coverage_world.hpp"
#include "run_options.hpp"
#include "uavsim/launch/launcher.hpp"
#include "uavsim/launch/run_options.hpp"

using namespace uavsim::missions::coverage;
using uavsim::launch::Launcher;
using Json = nlohmann::json;

namespace {

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
  --radio-technology T  on ns3: 802.15.4 (default) or 802.11 (802.11g ad hoc, 6 Mbit/s, DCF;
                      1500-byte frames)
  --radio-send-spread S  on ns3 without TDMA: frames enter the channel at seeded offsets up to S
                      seconds after they were sent, as agents on clocks of their own would send
                      them (0-1; 0: one step on 802.11, none on 802.15.4; default: the agents'
                      tick, 0.05 s, on 802.11, none on 802.15.4)
  --radio-tdma D      the seed's TDMA on either backend: slots of D seconds (0.001-1; at least
                      4.256 ms on simple, 4.576 ms on ns3) in a 1 s period, slot k vehicle k mod N
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
  std::fputs(uavsim::launch::floor_usage(22).c_str(), stderr);
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  CoverageRunOptions o;
  o.agent = uavsim::launch::sibling_program("coverage-agent");
  o.gcs_program = uavsim::launch::sibling_program("coverage-gcs");
  if (!parse_run_options(argc, argv, &o)) return usage();
  if (!run_options_agree(o)) return 2;
  std::sort(o.kills.begin(), o.kills.end());
  if (!uavsim::launch::resolve_run_files("coverage", &o, !o.no_record)) return 2;
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

  uavsim::launch::catch_interrupts();
  CoverageRun run(o, config, spec);
  if (!run.make_world()) return 4;
  Launcher launch("coverage-run", /*quiet=*/true);
  uavsim::launch::keep_run_summary(launch, "coverage", o);
  if (o.floor_s > 0.0) return run.run_floor(launch);
  run.start(launch);
  if (!run.failed()) {
    run.set_up();
    run.follow();
  }
  // 9. stop everything we started (the ground station prints its last map as it stops)
  launch.stop_all(30.0);
  const CoverageScore score = run.finish();
  run.print_summary(score);
  bool harness_failed = run.failed();
  if (!o.json_path.empty()) {
    const Json summary = run.summary_json(score);
    if (!launch.write_summary(o.json_path, summary)) harness_failed = true;
    const std::string run_summary = o.run_dir + "/summary.json";
    if (!o.map_png.empty() && o.json_path != run_summary &&
        !launch.write_summary(run_summary, summary))  // what plot_run.py reads
      harness_failed = true;
  }
  run.draw_map();
  return uavsim::launch::run_exit_code(harness_failed, score.success);
}
