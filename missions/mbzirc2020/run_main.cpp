// mbzirc2020-run: the whole MBZIRC 2020 balloon mission in the simulator, as on competition day
// (seed 7.2): uavsim-server on models/worlds/mbzirc2020.xml (seeded balloon positions, optional
// --record video), the ground station and one mission program per UAV, all on the server's lockstep
// clock at full speed. It prints the programs' progress and the simulator's events, then a summary
// scored from the sim API's ground truth (the programs never see it): balloons popped, mission
// time, crashes, the video.
//
// SIGINT or SIGTERM stops the run cleanly: the programs and the server are stopped, the summary so
// far is printed and written (JSON "interrupted": true, the interruption its "cause").
//
// Exit status: 0 only when every balloon is popped and no vehicle crashed (other than one killed on
// purpose with --kill, Competition Day 2's failed UAV). 1: the mission fell short; 2: usage; 4: the
// harness failed; 130: interrupted.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <regex>
#include <set>
#include <string>
#include <vector>

#include "uavsim/client/sim_connection.hpp"
#include "uavsim/common/parse_number.hpp"
#include "uavsim/launch/launcher.hpp"
#include "uavsim/launch/run_options.hpp"

namespace {

using Json = nlohmann::json;
using uavsim::client::SimConnection;
using uavsim::client::SimMessage;
using uavsim::launch::Launcher;

struct Options : uavsim::launch::RunOptions {
  double budget_s = 400.0;
  double wall_limit_s = 1800.0;
  std::string kill;                         // vehicle to kill right after its take-off
  double gcs_loss = 0.0;                    // the GCS link relay's loss probability, both vehicles
  double gcs_latency_s = 0.0;               // and its one-way latency
  std::string gcs_link_backend = "simple";  // the relay's channel: simple, or ns3's 802.11
  std::string camera_size = "384x216";
  double camera_fps = 15;
  std::string uav, gcs;
};

using uavsim::common::parse_double;
using uavsim::launch::parse_run_option;
using uavsim::launch::RunOptionParse;

int usage() {
  std::fprintf(stderr, R"(usage: mbzirc2020-run [options]
Runs the MBZIRC 2020 balloon mission (seed 7.2): server, ground station, two UAV programs, lockstep at full speed.
  --seed N            balloon positions and sensor noise (default 1)
  --world FILE        default models/worlds/mbzirc2020.xml
  --record FILE.mp4   video of the run (default video.mp4 in the run directory); --no-record: none
  --budget S          sim-time limit of the mission (default 400)
  --kill VEHICLE      kill this vehicle right after its take-off (Competition Day 2)
  --gcs-loss P        impair both UAVs' GCS links in the server's relay: drop each datagram with
                      probability P (0-1, seeded; default 0)
  --gcs-latency S     and deliver the rest S seconds of sim time later (default 0)
  --gcs-link-backend B  the relay's channel: simple (default: whole datagrams at the next control
                      step) or ns3 (each datagram over ns-3's 802.11g ad hoc between the UAV and a
                      ground node at the launch point; the server's --gcs-link-backend)
  --camera-size WxH   the UAV cameras' size (default 384x216: 39 x 21 deg as the seed's oCam-1CGN-U)
  --camera-fps F      the UAV cameras' frame rate (default 15)
  --realism LEVEL     field|ideal: the server's conditions (default: the world's; docs/results/field_conditions.md)
  --wind S,DIR[,GUST] the server's mean wind (m/s, from DIR degrees) and gust peak
  --json FILE         write the summary as JSON
  --run-dir DIR       everything of the run in DIR (default auto: runs/mbzirc2020-seedN-TIME):
                      video.mp4, summary.json, events.jsonl and tlogs (the server's --log-dir),
                      truth_VEHICLE.csv (ground truth at --truth-hz, default 10); scripts/plot_run.py
                      DIR plots it
  --no-run-dir        no run directory (same as --run-dir none)
  --record-camera C   the video's view: follow (default), follow:VEHICLE, top, overview, a camera
  --record-layout L   tiled (default: the UAVs' cameras beside the main view) or single
  --events FILE       write the sim's event log (JSON lines) at the end of the run
  --wall-limit S      wall-clock safety bound (default 1800)
  --quiet             only the summary
  --server/--uav/--gcs PATH  programs (default: beside this one / the build tree)
)");
  std::fputs(uavsim::launch::floor_usage(22).c_str(), stderr);
  return 2;
}

// the command line into o; false: not usable (usage)
bool parse_options(int argc, char** argv, Options* o, bool* record) {
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> const char* { return i + 1 < argc ? argv[++i] : nullptr; };
    const char* v = nullptr;
    bool ok = true;  // a number's text was whole and in range
    if (a == "--no-record")
      *record = false;
    else if (a == "--no-run-dir")
      o->run_dir = "none";
    else if (a == "--quiet")
      o->quiet = true;
    else if (a == "--help" || a == "-h")
      return false;
    else if ((v = next()) == nullptr)
      return false;
    else if (const auto common = parse_run_option(a, v, o); common != RunOptionParse::kNotCommon)
      ok = common == RunOptionParse::kTaken;
    else if (a == "--budget")
      ok = parse_double(v, 1.0, 36000.0, &o->budget_s);
    else if (a == "--wall-limit")
      ok = parse_double(v, 1.0, 1e6, &o->wall_limit_s);
    else if (a == "--kill")
      o->kill = v;
    else if (a == "--gcs-loss")
      ok = parse_double(v, 0.0, 1.0, &o->gcs_loss);
    else if (a == "--gcs-latency")
      ok = parse_double(v, 0.0, 60.0, &o->gcs_latency_s);
    else if (a == "--gcs-link-backend") {
      o->gcs_link_backend = v;
      ok = o->gcs_link_backend == "simple" || o->gcs_link_backend == "ns3";
      if (!ok) std::fprintf(stderr, "mbzirc2020-run: --gcs-link-backend needs simple or ns3\n");
    } else if (a == "--camera-size")
      o->camera_size = v;
    else if (a == "--camera-fps")
      ok = parse_double(v, 0.1, 1000.0, &o->camera_fps);
    else if (a == "--uav")
      o->uav = v;
    else if (a == "--gcs")
      o->gcs = v;
    else
      return false;
    if (!ok) return false;
  }
  return true;
}

// the harness's failures: said on stderr; the run then ends with kExitHarness
struct Harness {
  bool failed = false;
  void fail(const std::string& why) {
    std::fprintf(stderr, "mbzirc2020-run: %s\n", why.c_str());
    failed = true;
  }
};

// what the run learns from the event stream and the ground truth, for the score and the summary
struct Run {
  std::set<std::string> killed;
  std::set<std::string> took_off;  // the vehicles whose take-off event came
  double kill_check_s = -1.0;      // --kill: the armed pause at which the kill is decided
  std::vector<std::string> crashes;
  std::vector<std::string> vision_logs;  // the UAV programs' video logs, in the run directory
  bool collision = false;
  double first_armed_s = -1, last_pop_s = -1, end_sim_s = 0;
  int popped = 0, balloons_total = 0;
  Json summary;
};

// the ground station's failover (a UAV out, the other taking its side over) is the mission's, not
// the server's: told to the video's overlay ("gcs t=3.65 uav1 failed: out of the mission" =>
// uav1's line "failed: out of the mission")
void overlay_failover(SimConnection& api, const std::string& line) {
  static const std::regex failover_re(
      R"(^gcs t=\S+ (uav\d+) (.*(out of the mission|takes over).*)$)");
  std::smatch m;
  if (std::regex_search(line, m, failover_re)) {
    (void)api.request(
        {{"op", "overlay_note"}, {"text", m[2].str().substr(0, 80)}, {"vehicle", m[1].str()}});
  }
}

// 3. the ground station; its link ports (uav index -> port), read from its output
std::map<int, int> start_ground_station(Launcher& launch, const Options& o,
                                        const std::string& lockstep, Harness& h) {
  // the map outlives this call: the launcher keeps the callback for the whole run
  auto gcs_port = std::make_shared<std::map<int, int>>();
  const std::regex gcs_re(R"(gcs: uav(\d+) link on udp:[0-9.]+:(\d+))");
  launch.on_line([&launch, &o, gcs_port, gcs_re](const std::string& child, const std::string& l) {
    std::smatch m;
    if (child == "gcs" && std::regex_search(l, m, gcs_re)) {
      (*gcs_port)[std::stoi(m[1])] = std::stoi(m[2]);
    }
    if (!o.record.empty() && child == "gcs") overlay_failover(launch.api(), l);
  });
  if (auto g = launch.spawn("gcs", {o.gcs, "--uavs", "2"}, {lockstep}); !g) {
    h.fail("cannot start " + o.gcs);
  }
  while (!h.failed && gcs_port->size() < 2 && launch.wall_s() < 60 && !launch.programs_done() &&
         !uavsim::launch::interrupted()) {
    launch.pump(200);
  }
  if (!h.failed && gcs_port->size() < 2) h.fail("the ground station did not start");
  return *gcs_port;
}

// the server's GCS link relay in front of the station's port for UAV i (seed 6.3), impaired as
// asked; the port the UAV program is to send to, 0 after a failure
int open_gcs_link(SimConnection& api, const Options& o, int i, int gcs_port, Harness& h) {
  const auto r = api.request({{"op", "gcs_link_open"},
                              {"vehicle", i},
                              {"gcs_target_host", "127.0.0.1"},
                              {"gcs_target_port", gcs_port}});
  if (!r) {
    h.fail("gcs_link_open: " + r.message());
    return 0;
  }
  if (o.gcs_loss > 0.0 || o.gcs_latency_s > 0.0) {
    // impaired from t = 0, before the UAV program sends anything
    const auto ir = api.request({{"op", "gcs_link_impair"},
                                 {"vehicle", i},
                                 {"loss", o.gcs_loss},
                                 {"latency_s", o.gcs_latency_s}});
    if (!ir) {
      h.fail("gcs_link_impair: " + ir.message());
      return 0;
    }
  }
  return r->value("uav_port", 0);
}

// 3.-5. the ground station, the GCS links and the UAV programs; the clock goes once all three have
// joined the lockstep
void start_programs(Launcher& launch, const Options& o, Run& run, Harness& h) {
  SimConnection& api = launch.api();
  const std::string lockstep = launch.lockstep_env(0.05);
  std::map<int, int> gcs_port = start_ground_station(launch, o, lockstep, h);
  for (int i = 0; i < 2 && !h.failed; ++i) {
    const int uav_port = open_gcs_link(api, o, i, gcs_port[i], h);
    if (h.failed) break;
    // 4. the UAV programs
    const std::string name = "uav" + std::to_string(i);
    std::vector<std::string> argv{o.uav,
                                  "--index",
                                  std::to_string(i),
                                  "--mavlink",
                                  "tcp:127.0.0.1:" + std::to_string(launch.mavlink_port(name)),
                                  "--gcs",
                                  "127.0.0.1:" + std::to_string(uav_port)};
    if (!o.run_dir.empty()) {
      // what its vision saw, frame by frame (uavsim-videolog-export makes an MP4 of it)
      run.vision_logs.push_back(o.run_dir + "/" + name + "_vision.vlog");
      argv.insert(argv.end(), {"--video-log", run.vision_logs.back()});
    }
    if (!launch.spawn(name, argv, {lockstep})) {
      h.fail("cannot start " + o.uav);
    }
  }
  // 5. once all three have joined the lockstep, let the clock go
  if (!h.failed && !launch.wait_lockstep_clients(3, 120.0)) {
    h.fail("the mission programs did not join the lockstep");
  }
  if (!h.failed) {
    (void)api.resume();
    launch.say("mbzirc2020-run: seed " + std::to_string(o.seed) + ", budget " +
               std::to_string(static_cast<int>(o.budget_s)) + " s sim" +
               (o.kill.empty() ? "" : ", killing " + o.kill + " after its take-off"));
  }
}

// one sim event: noted for the score and printed
void on_sim_event(const Json& e, Launcher& launch, Run& run) {
  const std::string type = e.value("type", ""), veh = e.value("vehicle_name", "");
  const double t = e.value("time", 0.0);
  const std::string detail = e.value("detail", "");
  if (type == "takeoff" && run.first_armed_s < 0)
    run.first_armed_s = t;  // the GCS start: first take-off
  if (type == "balloon_popped") run.last_pop_s = t;
  if (type == "vehicle_killed") run.killed.insert(veh);
  if (type == "crash" && !run.killed.count(veh)) {
    run.crashes.push_back(veh + " at " + std::to_string(t) + " s: " + detail);
    run.collision = run.collision || detail.find("collision") != std::string::npos;
  }
  if (type == "balloon_popped" || type == "crash" || type == "vehicle_killed" ||
      type == "takeoff" || type == "touchdown") {
    char buf[256];
    std::snprintf(buf, sizeof(buf), "[event] t=%.2f %s %s %s", t, type.c_str(), veh.c_str(),
                  detail.c_str());
    launch.say(buf);
  }
  if (type == "takeoff") run.took_off.insert(veh);
}

// the sim events the API connection has received so far, each through on_sim_event
void read_sim_events(Launcher& launch, Run& run) {
  for (const SimMessage& m : launch.api().take_messages()) {
    if (m.kind() == "sim_event") on_sim_event(m.json, launch, run);
  }
}

// --kill, at a sim time that wall-clock timing cannot move: the clock holds at each check
// (pause_at, every kKillCheckPeriod_s from kFirstKillCheck_s), and the first check after the
// vehicle's take-off kills it. (Sent when the launcher read the take-off event, the kill fell a
// tick or two apart between runs of a seed: the launcher is not a lockstep client.)
constexpr double kFirstKillCheck_s = 3.0;  // the GCS starts the UAVs at 2.5 s; take-off ~2.8 s
constexpr double kKillCheckPeriod_s = 0.5;
constexpr double kLastKillCheck_s = 60.0;  // a vehicle not off the ground by then is not killed

void arm_kill_check(SimConnection& api, Run& run, double at_s) {
  run.kill_check_s = at_s;
  (void)api.request({{"op", "pause_at"}, {"time_s", at_s}});
}

// at a held kill check (the events up to it read): the kill, or the next check; then on
void kill_at_check(Launcher& launch, const Options& o, Run& run) {
  SimConnection& api = launch.api();
  read_sim_events(launch, run);
  if (run.took_off.count(o.kill)) {
    (void)api.request(
        {{"op", "kill_vehicle"}, {"vehicle", o.kill}, {"reason", "Competition Day 2 malfunction"}});
    run.killed.insert(o.kill);
    run.kill_check_s = -1.0;
  } else if (run.kill_check_s + kKillCheckPeriod_s <= kLastKillCheck_s) {
    arm_kill_check(api, run, run.kill_check_s + kKillCheckPeriod_s);
  } else {
    launch.say("mbzirc2020-run: " + o.kill + " never took off: not killed");
    run.kill_check_s = -1.0;
  }
  (void)api.resume();
}

// 6. follow the programs and the event stream until they finish or the budget is spent
void follow(Launcher& launch, const Options& o, Run& run, Harness& h) {
  SimConnection& api = launch.api();
  double last_status_wall_s = launch.wall_s();
  double sim_s = 0;
  while (!h.failed) {
    launch.pump(200);
    read_sim_events(launch, run);
    const bool all_done = launch.programs_done();
    const bool kill_pending = run.kill_check_s >= 0;
    if (launch.wall_s() - last_status_wall_s > (kill_pending ? 0.05 : 0.5) || all_done) {
      last_status_wall_s = launch.wall_s();
      if (const auto s = api.status(); s) {
        sim_s = s->value("time_s", 0.0);
        if (kill_pending && s->value("paused", false) && sim_s >= run.kill_check_s - 0.01) {
          kill_at_check(launch, o, run);
        }
      }
      launch.note_sim_time(sim_s);
    }
    if (all_done || uavsim::launch::interrupted()) break;
    if (sim_s >= o.budget_s - 0.01) {  // pause_at holds within a physics step of the budget
      launch.say("mbzirc2020-run: sim-time budget spent");
      break;
    }
    std::string failure;
    if (uavsim::launch::run_must_end(launch, "mbzirc2020-run", o.wall_limit_s, &failure)) {
      if (!failure.empty()) h.fail(failure);
      break;
    }
  }
}

// 7. score from ground truth, once the clock holds by itself at the end (pause_at; interrupted:
// as it stands)
void score(Launcher& launch, const Options& o, Run& run, const Harness& h) {
  SimConnection& api = launch.api();
  for (const double until_s = launch.wall_s() + 10.0;
       !h.failed && !uavsim::launch::interrupted() && launch.wall_s() < until_s; launch.pump(10)) {
    const auto st = api.status();
    if (!st || st->value("paused", false)) break;
  }
  if (const auto b = api.request({{"op", "balloons"}}); b) {
    run.end_sim_s = b->value("time_s", 0.0);
    for (const Json& x : b->at("balloons")) {
      ++run.balloons_total;
      if (x.value("popped", false)) {
        ++run.popped;
        run.last_pop_s = std::max(run.last_pop_s, x.value("popped_time_s", 0.0));
      }
    }
    run.summary["balloons"] = b->at("balloons");
  }
  if (!o.events_path.empty()) {
    if (const auto ev = api.request({{"op", "events"}}); ev) {
      std::ofstream f(o.events_path);
      for (const Json& e : ev->at("events")) f << e.dump() << "\n";
    }
  }
  // the relay's counters: what the impairment did to each GCS link
  run.summary["gcs_links"] = Json::array();
  for (int i = 0; i < 2; ++i) {
    if (const auto g = api.request({{"op", "gcs_link_stats"}, {"vehicle", i}}); g) {
      run.summary["gcs_links"].push_back(*g);
    }
  }
}

// 2.-7. the mission on a started server: the clock held at t = 0 with this seed, the programs,
// the run followed, the score
void run_mission(Launcher& launch, const Options& o, Run& run, Harness& h) {
  SimConnection& api = launch.api();
  // hold the clock and start from t = 0 with this seed, so every run of a seed starts alike
  (void)api.pause();
  (void)api.reset(o.seed);
  (void)api.subscribe_events();
  // the clock stops by itself when the last program leaves the lockstep or the budget is spent,
  // so the end of the run (its sim time, the score) is the same every run
  (void)api.request({{"op", "pause_at"}, {"time_s", o.budget_s}, {"lockstep_empty", true}});
  if (!o.kill.empty()) arm_kill_check(api, run, kFirstKillCheck_s);
  start_programs(launch, o, run, h);
  follow(launch, o, run, h);
  score(launch, o, run, h);
}

double mission_time_s(const Run& run) {
  return (run.first_armed_s >= 0 && run.last_pop_s >= 0) ? run.last_pop_s - run.first_armed_s : -1;
}

void print_summary(const Options& o, const Run& run, const Launcher& launch, bool success) {
  const double mission_s = mission_time_s(run);
  std::printf("==== MBZIRC 2020 balloons, seed %llu%s ====\n",
              static_cast<unsigned long long>(o.seed),
              o.kill.empty() ? "" : (" (" + o.kill + " killed after take-off)").c_str());
  std::printf("balloons popped: %d/%d\n", run.popped, run.balloons_total);
  if (mission_s >= 0) {
    std::printf("mission time: %.1f s sim (first take-off at t=%.1f s, last balloon at t=%.1f s)\n",
                mission_s, run.first_armed_s, run.last_pop_s);
  } else {
    std::printf("mission time: n/a\n");
  }
  std::printf("collisions between UAVs: %s\n", run.collision ? "yes" : "none");
  std::printf("crashes: %s\n", run.crashes.empty() ? "none" : "");
  for (const std::string& c : run.crashes) std::printf("  %s\n", c.c_str());
  if (!run.killed.empty())
    std::printf("killed on purpose: %s\n",
                *run.killed.begin() == "" ? "?" : run.killed.begin()->c_str());
  std::printf("sim time: %.1f s, wall time: %.1f s\n", run.end_sim_s, launch.wall_s());
  std::printf("video: %s\n", o.record.empty() ? "none" : o.record.c_str());
  for (const std::string& v : run.vision_logs) {
    std::printf("vision log: %s (uavsim-videolog-export %s --mp4 FILE)\n", v.c_str(), v.c_str());
  }
  if (!o.run_dir.empty()) {
    std::printf("run directory: %s (%llu ground-truth rows; plots: scripts/plot_run.py %s)\n",
                o.run_dir.c_str(), static_cast<unsigned long long>(launch.truth_rows()),
                o.run_dir.c_str());
  }
  std::printf("RESULT: %s%s\n", success ? "SUCCESS" : "FAILURE",
              uavsim::launch::interrupted() ? " (interrupted)" : "");
  std::fflush(stdout);
}

Json summary_json(const Options& o, const Run& run, const Launcher& launch, bool success) {
  Json summary = run.summary;
  summary["mission"] = "mbzirc2020";
  summary["run_dir"] = o.run_dir;
  summary["seed"] = o.seed;
  summary["gcs_link_backend"] = o.gcs_link_backend;
  summary["popped"] = run.popped;
  summary["total"] = run.balloons_total;
  summary["mission_time_s"] = mission_time_s(run);
  summary["start_time_s"] = run.first_armed_s;
  summary["last_pop_time_s"] = run.last_pop_s;
  summary["collision"] = run.collision;
  summary["crashes"] = run.crashes;
  summary["killed"] = std::vector<std::string>(run.killed.begin(), run.killed.end());
  summary["sim_time_s"] = run.end_sim_s;
  summary["wall_time_s"] = launch.wall_s();
  summary["video"] = o.record;
  summary["vision_logs"] = run.vision_logs;
  summary["success"] = success;
  return summary;
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  uavsim::launch::default_world_and_server(&o, "mbzirc2020.xml", UAVSIM_MODELS_DIR,
                                           UAVSIM_SERVER_PATH);
  o.uav = uavsim::launch::sibling_program("mbzirc2020-uav");
  o.gcs = uavsim::launch::sibling_program("mbzirc2020-gcs");
  bool record = true;
  if (!parse_options(argc, argv, &o, &record)) return usage();
  if (!uavsim::launch::resolve_run_files("mbzirc2020", &o, record)) return 2;
  const size_t x = o.camera_size.find('x');
  if (x == std::string::npos) return usage();
  const std::string cam_opts = "width=" + o.camera_size.substr(0, x) +
                               ",height=" + o.camera_size.substr(x + 1) +
                               ",fps=" + std::to_string(static_cast<int>(o.camera_fps));
  uavsim::launch::catch_interrupts();
  Launcher launch("mbzirc2020-run", o.quiet);
  uavsim::launch::keep_run_summary(launch, "mbzirc2020", o);
  Harness h;
  Run run;

  // 1. the server, on ephemeral ports, as fast as possible; then the mission on it
  std::vector<std::string> server_args{"--camera", "uav0_front:" + cam_opts, "--camera",
                                       "uav1_front:" + cam_opts};
  if (o.gcs_link_backend != "simple") {
    server_args.insert(server_args.end(), {"--gcs-link-backend", o.gcs_link_backend});
  }
  // instead of the mission: its floor, the two forward cameras the UAV programs subscribe to
  if (o.floor_s > 0.0) {
    return uavsim::launch::run_floor(launch, "mbzirc2020", o, server_args, "uav0_front,uav1_front");
  }
  if (auto started = uavsim::launch::start_run_server(launch, o, server_args); !started) {
    h.fail("the server did not start: " + started.message());
  } else if (launch.mavlink_port("uav0") == 0 || launch.mavlink_port("uav1") == 0) {
    h.fail("the server did not start (no API / MAVLink ports)");
  } else {
    run_mission(launch, o, run, h);
  }

  // 8. stop everything we started: the programs, then the server (it finishes the video)
  launch.stop_all(60.0);

  const bool success = !h.failed && !uavsim::launch::interrupted() && run.balloons_total > 0 &&
                       run.popped == run.balloons_total && run.crashes.empty();
  print_summary(o, run, launch, success);
  bool harness_failed = h.failed;
  if (!o.json_path.empty() &&
      !launch.write_summary(o.json_path, summary_json(o, run, launch, success)))
    harness_failed = true;
  return uavsim::launch::run_exit_code(harness_failed, success);
}
