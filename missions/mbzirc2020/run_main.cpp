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
#include <nlohmann/json.hpp>
#include <regex>
#include <set>
#include <string>
#include <vector>

#include "uavsim/client/sim_connection.hpp"
#include "uavsim/common/install_paths.hpp"
#include "uavsim/common/parse_number.hpp"
#include "uavsim/launch/launcher.hpp"

namespace {

using Json = nlohmann::json;
using uavsim::client::SimConnection;
using uavsim::client::SimMessage;
using uavsim::launch::Launcher;

struct Options {
  uint64_t seed = 1;
  std::string world;
  std::string record;  // empty: no video
  double budget_s = 400.0;
  double wall_limit_s = 1800.0;
  std::string kill;            // vehicle to kill right after its take-off
  double gcs_loss = 0.0;       // the GCS link relay's loss probability, both vehicles
  double gcs_latency_s = 0.0;  // and its one-way latency
  std::string json_path;
  std::string events_path;  // the sim's event log, one JSON line per event
  std::string realism;      // --realism for the server (empty: the world's)
  std::string wind;         // --wind for the server
  std::string camera_size = "384x216";
  double camera_fps = 15;
  std::string run_dir = "auto";          // --run-dir: video, summary, events, logs, ground truth
  std::string record_camera = "follow";  // the server's --record-camera
  std::string record_layout = "tiled";   // the server's --record-layout: the UAVs' cameras beside
  double truth_hz = 10.0;
  bool quiet = false;
  std::string server, uav, gcs;
};

using uavsim::common::parse_double;
using uavsim::common::parse_integer;

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
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  // an install's own server and models (PREFIX/bin, PREFIX/share/uavsim/models), else the build's
  o.world = uavsim::common::find_models_dir("", UAVSIM_MODELS_DIR).path + "/worlds/mbzirc2020.xml";
  o.server = uavsim::common::installed_or_built_program("uavsim-server", UAVSIM_SERVER_PATH);
  o.uav = uavsim::launch::sibling_program("mbzirc2020-uav");
  o.gcs = uavsim::launch::sibling_program("mbzirc2020-gcs");
  bool record = true;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> const char* { return i + 1 < argc ? argv[++i] : nullptr; };
    const char* v = nullptr;
    bool ok = true;  // a number's text was whole and in range
    if (a == "--no-record")
      record = false;
    else if (a == "--no-run-dir")
      o.run_dir = "none";
    else if (a == "--quiet")
      o.quiet = true;
    else if (a == "--help" || a == "-h")
      return usage();
    else if ((v = next()) == nullptr)
      return usage();
    else if (a == "--seed") {
      if (!parse_integer<std::uint64_t>(v, 0, UINT64_MAX, &o.seed)) return usage();
    } else if (a == "--world")
      o.world = v;
    else if (a == "--record")
      o.record = v;
    else if (a == "--budget")
      ok = parse_double(v, 1.0, 36000.0, &o.budget_s);
    else if (a == "--wall-limit")
      ok = parse_double(v, 1.0, 1e6, &o.wall_limit_s);
    else if (a == "--kill")
      o.kill = v;
    else if (a == "--gcs-loss")
      ok = parse_double(v, 0.0, 1.0, &o.gcs_loss);
    else if (a == "--gcs-latency")
      ok = parse_double(v, 0.0, 60.0, &o.gcs_latency_s);
    else if (a == "--json")
      o.json_path = v;
    else if (a == "--run-dir")
      o.run_dir = v;
    else if (a == "--record-camera")
      o.record_camera = v;
    else if (a == "--record-layout")
      o.record_layout = v;
    else if (a == "--truth-hz")
      ok = parse_double(v, 0.01, 1000.0, &o.truth_hz);
    else if (a == "--events")
      o.events_path = v;
    else if (a == "--realism")
      o.realism = v;
    else if (a == "--wind")
      o.wind = v;
    else if (a == "--camera-size")
      o.camera_size = v;
    else if (a == "--camera-fps")
      ok = parse_double(v, 0.1, 1000.0, &o.camera_fps);
    else if (a == "--server")
      o.server = v;
    else if (a == "--uav")
      o.uav = v;
    else if (a == "--gcs")
      o.gcs = v;
    else
      return usage();
    if (!ok) return usage();
  }
  if (const auto files = uavsim::launch::resolve_run_files("mbzirc2020", o.seed, o.run_dir,
                                                           o.record, o.json_path, record);
      !files) {
    std::fprintf(stderr, "mbzirc2020-run: %s\n", files.message().c_str());
    return 2;
  } else {
    o.run_dir = files->dir;
    o.record = files->video;
    o.json_path = files->summary;
  }
  const size_t x = o.camera_size.find('x');
  if (x == std::string::npos) return usage();
  const std::string cam_opts = "width=" + o.camera_size.substr(0, x) +
                               ",height=" + o.camera_size.substr(x + 1) +
                               ",fps=" + std::to_string(static_cast<int>(o.camera_fps));
  uavsim::launch::catch_interrupts();
  Launcher launch("mbzirc2020-run", o.quiet);
  launch.keep_summary(o.json_path,
                      {{"mission", "mbzirc2020"}, {"seed", o.seed}, {"run_dir", o.run_dir}});
  int harness_error = 0;
  auto fail = [&](const std::string& why) {
    std::fprintf(stderr, "mbzirc2020-run: %s\n", why.c_str());
    harness_error = 4;
  };

  // 1. the server, on ephemeral ports, as fast as possible
  uavsim::launch::ServerSpec spec;
  spec.path = o.server;
  spec.world = o.world;
  spec.extra_args = {"--seed",   std::to_string(o.seed),  "--camera", "uav0_front:" + cam_opts,
                     "--camera", "uav1_front:" + cam_opts};
  if (!o.record.empty()) {
    spec.extra_args.insert(spec.extra_args.end(),
                           {"--record", o.record, "--record-camera", o.record_camera,
                            "--record-layout", o.record_layout});
  }
  if (!o.run_dir.empty()) {
    spec.extra_args.insert(spec.extra_args.end(), {"--log-dir", o.run_dir});
    launch.record_truth(o.run_dir, o.truth_hz);
  }
  if (!o.realism.empty()) spec.extra_args.insert(spec.extra_args.end(), {"--realism", o.realism});
  if (!o.wind.empty()) spec.extra_args.insert(spec.extra_args.end(), {"--wind", o.wind});
  std::set<std::string> killed;
  Json summary;
  int popped = 0, balloons_total = 0;
  std::vector<std::string> crashes;
  std::vector<std::string> vision_logs;  // the UAV programs' video logs, in the run directory
  bool collision = false;
  double first_armed_s = -1, last_pop_s = -1, end_sim_s = 0;

  if (auto started = launch.start_server(spec); !started) {
    fail("the server did not start: " + started.message());
  } else if (launch.mavlink_port("uav0") == 0 || launch.mavlink_port("uav1") == 0) {
    fail("the server did not start (no API / MAVLink ports)");
  } else {
    SimConnection& api = launch.api();
    // 2. hold the clock and start from t = 0 with this seed, so every run of a seed starts alike
    (void)api.pause();
    (void)api.reset(o.seed);
    (void)api.subscribe_events();
    // the clock stops by itself when the last program leaves the lockstep or the budget is spent,
    // so the end of the run (its sim time, the score) is the same every run
    (void)api.request({{"op", "pause_at"}, {"time_s", o.budget_s}, {"lockstep_empty", true}});
    const std::string lockstep = launch.lockstep_env(0.05);

    // 3. the ground station; its link ports, then the server's GCS link relay in front of each
    // (seed 6.3)
    std::map<int, int> gcs_port;
    const std::regex gcs_re(R"(gcs: uav(\d+) link on udp:[0-9.]+:(\d+))");
    launch.on_line([&](const std::string& child, const std::string& l) {
      std::smatch m;
      if (child == "gcs" && std::regex_search(l, m, gcs_re)) {
        gcs_port[std::stoi(m[1])] = std::stoi(m[2]);
      }
      // the ground station's failover (a UAV out, the other taking its side over) is the
      // mission's, not the server's: told to the video's overlay
      // ("gcs t=3.65 uav1 failed: out of the mission" => uav1's line "failed: out of the mission")
      static const std::regex failover_re(
          R"(^gcs t=\S+ (uav\d+) (.*(out of the mission|takes over).*)$)");
      if (!o.record.empty() && child == "gcs" && std::regex_search(l, m, failover_re)) {
        (void)api.request(
            {{"op", "overlay_note"}, {"text", m[2].str().substr(0, 80)}, {"vehicle", m[1].str()}});
      }
    });
    if (auto g = launch.spawn("gcs", {o.gcs, "--uavs", "2"}, {lockstep}); !g) {
      fail("cannot start " + o.gcs);
    }
    while (!harness_error && gcs_port.size() < 2 && launch.wall_s() < 60 &&
           !launch.programs_done() && !uavsim::launch::interrupted()) {
      launch.pump(200);
    }
    if (!harness_error && gcs_port.size() < 2) fail("the ground station did not start");
    for (int i = 0; i < 2 && !harness_error; ++i) {
      const auto r = api.request({{"op", "gcs_link_open"},
                                  {"vehicle", i},
                                  {"gcs_target_host", "127.0.0.1"},
                                  {"gcs_target_port", gcs_port[i]}});
      if (!r) {
        fail("gcs_link_open: " + r.message());
        break;
      }
      const int uav_port = r->value("uav_port", 0);
      if (o.gcs_loss > 0.0 || o.gcs_latency_s > 0.0) {
        // impaired from t = 0, before the UAV program sends anything
        const auto ir = api.request({{"op", "gcs_link_impair"},
                                     {"vehicle", i},
                                     {"loss", o.gcs_loss},
                                     {"latency_s", o.gcs_latency_s}});
        if (!ir) {
          fail("gcs_link_impair: " + ir.message());
          break;
        }
      }
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
        vision_logs.push_back(o.run_dir + "/" + name + "_vision.vlog");
        argv.insert(argv.end(), {"--video-log", vision_logs.back()});
      }
      if (!launch.spawn(name, argv, {lockstep})) {
        fail("cannot start " + o.uav);
      }
    }
    // 5. once all three have joined the lockstep, let the clock go
    if (!harness_error && !launch.wait_lockstep_clients(3, 120.0)) {
      fail("the mission programs did not join the lockstep");
    }
    if (!harness_error) {
      (void)api.resume();
      launch.say("mbzirc2020-run: seed " + std::to_string(o.seed) + ", budget " +
                 std::to_string(static_cast<int>(o.budget_s)) + " s sim" +
                 (o.kill.empty() ? "" : ", killing " + o.kill + " after its take-off"));
    }

    // 6. follow the programs and the event stream until they finish or the budget is spent
    double last_status_wall_s = launch.wall_s();
    double sim_s = 0;
    while (!harness_error) {
      launch.pump(200);
      for (const SimMessage& m : api.take_messages()) {
        if (m.kind() != "sim_event") continue;
        const Json& e = m.json;
        const std::string type = e.value("type", ""), veh = e.value("vehicle_name", "");
        const double t = e.value("time", 0.0);
        const std::string detail = e.value("detail", "");
        if (type == "takeoff" && first_armed_s < 0)
          first_armed_s = t;  // the GCS start: first take-off
        if (type == "balloon_popped") last_pop_s = t;
        if (type == "vehicle_killed") killed.insert(veh);
        if (type == "crash" && !killed.count(veh)) {
          crashes.push_back(veh + " at " + std::to_string(t) + " s: " + detail);
          collision = collision || detail.find("collision") != std::string::npos;
        }
        if (type == "balloon_popped" || type == "crash" || type == "vehicle_killed" ||
            type == "takeoff" || type == "touchdown") {
          char buf[256];
          std::snprintf(buf, sizeof(buf), "[event] t=%.2f %s %s %s", t, type.c_str(), veh.c_str(),
                        detail.c_str());
          launch.say(buf);
        }
        if (type == "takeoff" && veh == o.kill && !killed.count(veh)) {
          (void)api.request({{"op", "kill_vehicle"},
                             {"vehicle", veh},
                             {"reason", "Competition Day 2 malfunction"}});
          killed.insert(veh);
        }
      }
      const bool all_done = launch.programs_done();
      if (launch.wall_s() - last_status_wall_s > 0.5 || all_done) {
        last_status_wall_s = launch.wall_s();
        if (const auto s = api.status(); s) sim_s = s->value("time_s", 0.0);
        launch.note_sim_time(sim_s);
      }
      if (all_done || uavsim::launch::interrupted()) break;
      if (sim_s >= o.budget_s - 0.01) {  // pause_at holds within a physics step of the budget
        launch.say("mbzirc2020-run: sim-time budget spent");
        break;
      }
      if (launch.wall_s() > o.wall_limit_s) {
        launch.say("mbzirc2020-run: wall-clock limit reached");
        break;
      }
      if (launch.server_exited()) {
        fail(launch.server_end());
        break;
      }
      if (!launch.records_error().empty()) {
        fail("the run's records cannot be written: " + launch.records_error());
        break;
      }
    }

    // the clock holds by itself at the end (pause_at): score once it does (interrupted: as it
    // stands)
    for (const double until_s = launch.wall_s() + 10.0;
         !harness_error && !uavsim::launch::interrupted() && launch.wall_s() < until_s;
         launch.pump(10)) {
      const auto st = api.status();
      if (!st || st->value("paused", false)) break;
    }
    // 7. score from ground truth
    if (const auto b = api.request({{"op", "balloons"}}); b) {
      end_sim_s = b->value("time_s", 0.0);
      for (const Json& x : b->at("balloons")) {
        ++balloons_total;
        if (x.value("popped", false)) {
          ++popped;
          last_pop_s = std::max(last_pop_s, x.value("popped_time_s", 0.0));
        }
      }
      summary["balloons"] = b->at("balloons");
    }
    if (!o.events_path.empty()) {
      if (const auto ev = api.request({{"op", "events"}}); ev) {
        std::ofstream f(o.events_path);
        for (const Json& e : ev->at("events")) f << e.dump() << "\n";
      }
    }
    // the relay's counters: what the impairment did to each GCS link
    summary["gcs_links"] = Json::array();
    for (int i = 0; i < 2; ++i) {
      if (const auto g = api.request({{"op", "gcs_link_stats"}, {"vehicle", i}}); g) {
        summary["gcs_links"].push_back(*g);
      }
    }
  }

  // 8. stop everything we started: the programs, then the server (it finishes the video)
  launch.stop_all(60.0);

  const bool success = harness_error == 0 && !uavsim::launch::interrupted() && balloons_total > 0 &&
                       popped == balloons_total && crashes.empty();
  const double mission_s =
      (first_armed_s >= 0 && last_pop_s >= 0) ? last_pop_s - first_armed_s : -1;
  std::printf("==== MBZIRC 2020 balloons, seed %llu%s ====\n",
              static_cast<unsigned long long>(o.seed),
              o.kill.empty() ? "" : (" (" + o.kill + " killed after take-off)").c_str());
  std::printf("balloons popped: %d/%d\n", popped, balloons_total);
  if (mission_s >= 0) {
    std::printf("mission time: %.1f s sim (first take-off at t=%.1f s, last balloon at t=%.1f s)\n",
                mission_s, first_armed_s, last_pop_s);
  } else {
    std::printf("mission time: n/a\n");
  }
  std::printf("collisions between UAVs: %s\n", collision ? "yes" : "none");
  std::printf("crashes: %s\n", crashes.empty() ? "none" : "");
  for (const std::string& c : crashes) std::printf("  %s\n", c.c_str());
  if (!killed.empty())
    std::printf("killed on purpose: %s\n", *killed.begin() == "" ? "?" : killed.begin()->c_str());
  std::printf("sim time: %.1f s, wall time: %.1f s\n", end_sim_s, launch.wall_s());
  std::printf("video: %s\n", o.record.empty() ? "none" : o.record.c_str());
  for (const std::string& v : vision_logs) {
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

  if (!o.json_path.empty()) {
    summary["mission"] = "mbzirc2020";
    summary["run_dir"] = o.run_dir;
    summary["seed"] = o.seed;
    summary["popped"] = popped;
    summary["total"] = balloons_total;
    summary["mission_time_s"] = mission_s;
    summary["start_time_s"] = first_armed_s;
    summary["last_pop_time_s"] = last_pop_s;
    summary["collision"] = collision;
    summary["crashes"] = crashes;
    summary["killed"] = std::vector<std::string>(killed.begin(), killed.end());
    summary["sim_time_s"] = end_sim_s;
    summary["wall_time_s"] = launch.wall_s();
    summary["video"] = o.record;
    summary["vision_logs"] = vision_logs;
    summary["success"] = success;
    if (!launch.write_summary(o.json_path, summary)) harness_error = 4;
  }
  return uavsim::launch::run_exit_code(harness_error != 0, success);
}
