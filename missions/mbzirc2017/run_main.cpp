// mbzirc2017-run: the MBZIRC 2017 landing (seed 7.1) in the simulator, as on competition day:
// uavsim-server on models/worlds/mbzirc2017.xml (the truck driven by a seeded "person", optional
// --record video) and the UAV program on the server's lockstep clock at full speed. It prints the
// program's progress (state changes, first sighting, interception point, touchdown) and the
// simulator's events, then a summary scored from the sim API's ground truth, which the program
// never sees: landed on the deck (the landed_on_target event, and still carried by the truck 5 s
// later), time from take-off to touchdown, relative speed at touchdown, distance from the marker's
// centre, crashes.
//
// Where and how fast: --start-phase F starts the UAV when the truck has driven the fraction F of a
// lap of the eight (at its speed then; `random`: F drawn from the seed), so that the UAV meets it
// anywhere on the eight; --truck-speed-kmh sets its speed. The summary says where on the eight
// (crossing, straight, curve) the UAV began its approach and touched down, and the near misses: the
// smallest clearance between the UAV's colliding geoms and the cab (and the chassis), and the
// skids' margin to the deck's edges while at its height, from the ground truth at every lockstep
// tick.
//
// Faults: --lose-low-off-centre puts the UAV's GPS 1 m off and blacks the camera out as its skids
// first come within 1 m of the deck: the marker lost while the UAV's estimate has it 1 m off the
// centre (the open-loop descent of issue 36 hit the cab from there); --random-blackouts N blacks
// the camera out N times at seeded moments (10-100 s after the start, 0.5-4 s each);
// --blackout-first-pass blacks the camera out when the UAV first starts waiting for the truck at
// its interception point (for longer than its 12 s search: the FSM must go back to Intercept);
// --lose-in-approach blacks it out for 4 s when the UAV first starts its approach (the truck lost
// from view: climb, re-acquire or go back to the centre). With a fault the launcher joins the
// lockstep itself and injects it at a tick, from the program's output stamped before that tick, so
// a seed's run is the same every time.
//
// SIGINT or SIGTERM stops the run cleanly: the program and the server are stopped, the summary so
// far is printed and written (JSON "interrupted": true, the interruption its "cause").
//
// Exit status: 0 only when the UAV landed on the deck, stayed there 5 s and nothing crashed.
// 1: the mission fell short; 2: usage; 4: the harness failed; 130: interrupted.
#include <cstdint>
#include <cstdio>
#include <string>

#include "landing_run.hpp"
#include "uavsim/common/parse_number.hpp"
#include "uavsim/launch/launcher.hpp"
#include "uavsim/launch/run_options.hpp"

using namespace uavsim::missions::mbzirc2017;
using uavsim::launch::Launcher;

namespace {

int usage() {
  std::fprintf(stderr, R"(usage: mbzirc2017-run [options]
Runs the MBZIRC 2017 landing on the moving truck (seed 7.1): server and UAV program, lockstep at full speed.
  --seed N               the driver's wander and sensor noise (default 1)
  --truck-speed-kmh V    the truck's speed for the first 8 minutes (default the world's: 15; 0-60);
                         random: drawn from the seed, uniform in the rules' 5-20 km/h
  --phase fast|slow      slow: start the UAV in the 5 km/h phase (same as --start-time 480)
  --start-time S         let the truck drive S seconds of sim time before the UAV starts (0-3600)
  --start-phase F|random start when the truck has driven F (0-1) of a lap of the eight at its speed
                         (after the 480 s of the first speed with --phase slow); random: F from the seed
  --random-blackouts N   black the camera out N times (0-20) at moments drawn from the seed, 10-100 s
                         after the start, 0.5-4 s each
  --blackout-first-pass  black the camera out for 14 s when the UAV first sets off to intercept
  --lose-in-approach     black the camera out for 4 s when the UAV first starts its approach
  --lose-low-off-centre  when the UAV's skids first come within 1 m of the deck in its approach: its GPS
                         1 m off (towards the truck's rear: the UAV believes itself 1 m behind the
                         marker, its control pulls it towards the cab) and the camera black, both for 6 s
  --record FILE.mp4      video of the run (--record-camera; default video.mp4 in the run directory)
  --no-record            no video
  --realism LEVEL        field|ideal: the server's conditions (default: the world's)
  --wind S,DIR[,GUST]    the server's mean wind (m/s, from DIR degrees) and gust peak
  --json FILE            write the summary as JSON
  --run-dir DIR          everything of the run in DIR (default auto: runs/mbzirc2017-seedN-TIME):
                         video.mp4, summary.json, events.jsonl and tlogs (the server's --log-dir),
                         truth_VEHICLE.csv and truck_NAME.csv (ground truth at --truth-hz, default
                         10); scripts/plot_run.py DIR plots it
  --no-run-dir           no run directory (same as --run-dir none)
  --record-camera C      the video's view: follow (default), follow:VEHICLE, top, overview, a camera
  --record-layout L      tiled (default: the UAV's camera beside the main view) or single
  --events FILE          write the sim's event log (JSON lines) at the end of the run
  --budget S             sim seconds the UAV gets after its start (default 300)
  --wall-limit S         wall-clock safety bound (default 1200)
  --quiet                only the summary
  --world FILE           default models/worlds/mbzirc2017.xml
  --server/--uav PATH    programs (default: the build tree's server / beside this one)
)");
  std::fputs(uavsim::launch::floor_usage(25).c_str(), stderr);
  return 2;
}

using uavsim::common::parse_double;
using uavsim::common::parse_integer;
using uavsim::launch::parse_run_option;
using uavsim::launch::RunOptionParse;

// the command line into o; false: not usable (usage)
bool parse_options(int argc, char** argv, LandingRunOptions* o) {
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> const char* { return i + 1 < argc ? argv[++i] : nullptr; };
    const char* v = nullptr;
    if (a == "--quiet") {
      o->quiet = true;
    } else if (a == "--blackout-first-pass") {
      o->blackout_first_pass = true;
    } else if (a == "--lose-in-approach") {
      o->lose_in_approach = true;
    } else if (a == "--lose-low-off-centre") {
      o->lose_low_off_centre = true;
    } else if (a == "--no-record") {
      o->no_record = true;
    } else if (a == "--no-run-dir") {
      o->run_dir = "none";
    } else if (a == "--help" || a == "-h") {
      return false;
    } else if ((v = next()) == nullptr) {
      return false;
    } else if (const auto common = parse_run_option(a, v, o);
               common != RunOptionParse::kNotCommon) {
      if (common == RunOptionParse::kBad) return false;
    } else if (a == "--truck-speed-kmh") {
      if (std::string(v) == "random") {
        o->random_truck_speed = true;
      } else if (!parse_double(v, 0.0, kMaxKmh, &o->truck_speed_kmh)) {
        return false;
      }
    } else if (a == "--phase") {
      if (std::string(v) == "slow") {
        o->start_time_s = 480.0;
        o->slow_phase = true;
      } else if (std::string(v) != "fast") {
        return false;
      }
    } else if (a == "--start-phase") {
      double f = 0.0;
      if (std::string(v) == "random") {
        o->random_start_phase = true;
      } else if (parse_double(v, 0.0, 1.0, &f)) {
        o->start_phase = f;
      } else {
        return false;
      }
    } else if (a == "--random-blackouts") {
      if (!parse_integer<int>(v, 0, kMaxBlackouts, &o->random_blackouts)) return false;
    } else if (a == "--start-time") {
      if (!parse_double(v, 0.0, kMaxStart_s, &o->start_time_s)) return false;
    } else if (a == "--budget") {
      if (!parse_double(v, 1.0, 36000.0, &o->budget_s)) return false;
    } else if (a == "--wall-limit") {
      if (!parse_double(v, 1.0, 86400.0, &o->wall_limit_s)) return false;
    } else if (a == "--uav") {
      o->uav = v;
    } else {
      return false;
    }
  }
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  LandingRunOptions o;
  uavsim::launch::default_world_and_server(&o, "mbzirc2017.xml", UAVSIM_MODELS_DIR,
                                           UAVSIM_SERVER_PATH);
  o.uav = uavsim::launch::sibling_program("mbzirc2017-uav");
  if (!parse_options(argc, argv, &o)) return usage();
  if (!uavsim::launch::resolve_run_files("mbzirc2017", &o, !o.no_record)) return 2;
  uavsim::launch::catch_interrupts();
  Launcher launch("mbzirc2017-run", o.quiet);
  uavsim::launch::keep_run_summary(launch, "mbzirc2017", o);
  LandingRun run(launch, o);
  if (const int code = run.prepare(); code != 0) return code;
  if (o.floor_s > 0.0) return run.run_floor();
  run.start_server();
  // the launcher always joins the lockstep: it scores the near misses at every tick (and injects
  // the faults there)
  if (!run.failed()) {
    run.set_up();
    run.follow();
    run.finish();
  }
  launch.stop_all(60.0);
  run.clean_up();
  const bool success = run.success();
  run.print_summary(success);
  bool harness_failed = run.failed();
  if (!o.json_path.empty() && !launch.write_summary(o.json_path, run.summary_json(success)))
    harness_failed = true;
  return uavsim::launch::run_exit_code(harness_failed, success);
}
