// mbzirc2017-run: the MBZIRC 2017 landing (seed 7.1) in the simulator, as on competition day:
// uavsim-server on models/worlds/mbzirc2017.xml (the truck driven by a seeded "person", optional
// --record video) and the UAV program on the server's lockstep clock at full speed. It prints the
// program's progress (state changes, first sighting, interception point, touchdown) and the
// simulator's events, then a summary scored from the sim API's ground truth, which the program
// never sees: landed on the deck (the landed_on_target event, and still carried by the truck 5 s
// later), time from take-off to touchdown, relative speed at touchdown, distance from the marker's
// centre, crashes.
//
// Faults: --blackout-first-pass blacks the camera out when the UAV first starts waiting for the
// truck at its interception point (for longer than its 12 s search: the FSM must go back to
// Intercept);
// --lose-in-approach blacks it out for 4 s when the UAV first starts its approach (the truck lost
// from view: climb, re-acquire or go back to the centre). With a fault the launcher joins the
// lockstep itself and injects it at a tick, from the program's output stamped before that tick, so
// a seed's run is the same every time.
//
// Exit status: 0 only when the UAV landed on the deck, stayed there 5 s and nothing crashed.
// 1: the mission fell short; 2: usage; 4: the harness failed.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <nlohmann/json.hpp>
#include <optional>
#include <regex>
#include <sstream>
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

constexpr double kLockstepPeriod_s = 0.05;     // the UAV program's and the fault injector's ticks
constexpr double kStayOnDeck_s = 5.0;          // scored: still carried this long after touchdown
constexpr double kPauseSlack_s = 0.01;  // a pause_at holds the clock within a physics step of its time
constexpr double kFirstPassBlackout_s = 14.0;  // longer than the 12 s search of Wait Until Visible
constexpr double kApproachBlackout_s = 4.0;    // longer than the 1 s after which the marker is lost
constexpr double kMaxKmh = 60.0;
constexpr double kMaxStart_s = 3600.0;

struct Options {
  uint64_t seed = 1;
  std::string world;
  double truck_speed_kmh = 0.0;  // 0: the world's (15 km/h)
  double start_time_s = 0.0;     // the UAV starts at this sim time (480: the 5 km/h phase)
  std::string record;
  std::string json_path;
  std::string events_path;  // the sim's event log, one JSON line per event
  std::string realism;      // --realism for the server (empty: the world's)
  std::string wind;         // --wind for the server
  std::string run_dir = "auto";          // --run-dir: video, summary, events, logs, ground truth
  bool no_record = false;                // --no-record: no video
  std::string record_camera = "follow";  // the server's --record-camera
  std::string record_layout = "tiled";   // the server's --record-layout: the UAV's camera beside
  double truth_hz = 10.0;
  bool quiet = false;
  bool blackout_first_pass = false;
  bool lose_in_approach = false;
  double budget_s = 300.0;  // sim seconds after the UAV's start
  double wall_limit_s = 1200.0;
  std::string server, uav;
};

int usage() {
  std::fprintf(stderr, R"(usage: mbzirc2017-run [options]
Runs the MBZIRC 2017 landing on the moving truck (seed 7.1): server and UAV program, lockstep at full speed.
  --seed N               the driver's wander and sensor noise (default 1)
  --truck-speed-kmh V    the truck's speed for the first 8 minutes (default the world's: 15; 0-60)
  --phase fast|slow      slow: start the UAV in the 5 km/h phase (same as --start-time 480)
  --start-time S         let the truck drive S seconds of sim time before the UAV starts (0-3600)
  --blackout-first-pass  black the camera out for 14 s when the UAV first sets off to intercept
  --lose-in-approach     black the camera out for 4 s when the UAV first starts its approach
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
  return 2;
}

using uavsim::common::parse_double;
using uavsim::common::parse_integer;

// The world with the truck's first speed replaced, written beside the temporary files (its include
// made absolute). Empty on failure.
std::string world_with_speed(const std::string& world, double kmh, uint64_t seed) {
  std::ifstream in(world);
  if (!in) return "";
  std::stringstream ss;
  ss << in.rdbuf();
  std::string text = ss.str();
  const std::string dir = world.substr(0, world.rfind('/') + 1);
  text = std::regex_replace(text, std::regex(R"(file="\.\./)"), "file=\"" + dir + "../");
  char speed[64];
  std::snprintf(speed, sizeof(speed), "data=\"%.6g 5 480 0\"", kmh);
  text = std::regex_replace(text, std::regex(R"((name="uavsim:truck:speed"\s+)data="[^"]*")"),
                            std::string("$1") + speed);
  const char* tmp = std::getenv("TMPDIR");
  const std::string path = std::string(tmp != nullptr && *tmp != '\0' ? tmp : "/tmp") +
                           "/mbzirc2017_" + std::to_string(getpid()) + "_" + std::to_string(seed) +
                           ".xml";
  std::ofstream out(path);
  out << text;
  return out ? path : "";
}

// "uav0 t=12.35 state Intercept -> WaitUntilVisible: ..." => (12.35, "WaitUntilVisible")
std::optional<std::pair<double, std::string>> state_change(const std::string& line) {
  static const std::regex re(R"(t=([0-9.]+) state \w+ -> (\w+))");
  std::smatch m;
  if (!std::regex_search(line, m, re)) return std::nullopt;
  return std::make_pair(std::stod(m[1]), m[2].str());
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  // an install's own server and models (PREFIX/bin, PREFIX/share/uavsim/models), else the build's
  o.world = uavsim::common::find_models_dir("", UAVSIM_MODELS_DIR).path + "/worlds/mbzirc2017.xml";
  o.server = uavsim::common::installed_or_built_program("uavsim-server", UAVSIM_SERVER_PATH);
  o.uav = uavsim::launch::sibling_program("mbzirc2017-uav");
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> const char* { return i + 1 < argc ? argv[++i] : nullptr; };
    const char* v = nullptr;
    if (a == "--quiet") {
      o.quiet = true;
    } else if (a == "--blackout-first-pass") {
      o.blackout_first_pass = true;
    } else if (a == "--lose-in-approach") {
      o.lose_in_approach = true;
    } else if (a == "--no-record") {
      o.no_record = true;
    } else if (a == "--no-run-dir") {
      o.run_dir = "none";
    } else if (a == "--help" || a == "-h") {
      return usage();
    } else if ((v = next()) == nullptr) {
      return usage();
    } else if (a == "--seed") {
      if (!parse_integer<std::uint64_t>(v, 0, UINT64_MAX, &o.seed)) return usage();
    } else if (a == "--truck-speed-kmh") {
      if (!parse_double(v, 0.0, kMaxKmh, &o.truck_speed_kmh)) return usage();
    } else if (a == "--phase") {
      if (std::string(v) == "slow") {
        o.start_time_s = 480.0;
      } else if (std::string(v) != "fast") {
        return usage();
      }
    } else if (a == "--start-time") {
      if (!parse_double(v, 0.0, kMaxStart_s, &o.start_time_s)) return usage();
    } else if (a == "--record") {
      o.record = v;
    } else if (a == "--json") {
      o.json_path = v;
    } else if (a == "--run-dir") {
      o.run_dir = v;
    } else if (a == "--record-camera") {
      o.record_camera = v;
    } else if (a == "--record-layout") {
      o.record_layout = v;
    } else if (a == "--truth-hz") {
      if (!parse_double(v, 0.01, 1000.0, &o.truth_hz)) return usage();
    } else if (a == "--events") {
      o.events_path = v;
    } else if (a == "--realism") {
      o.realism = v;
    } else if (a == "--wind") {
      o.wind = v;
    } else if (a == "--budget") {
      if (!parse_double(v, 1.0, 36000.0, &o.budget_s)) return usage();
    } else if (a == "--wall-limit") {
      if (!parse_double(v, 1.0, 86400.0, &o.wall_limit_s)) return usage();
    } else if (a == "--world") {
      o.world = v;
    } else if (a == "--server") {
      o.server = v;
    } else if (a == "--uav") {
      o.uav = v;
    } else {
      return usage();
    }
  }

  if (const auto files = uavsim::launch::resolve_run_files("mbzirc2017", o.seed, o.run_dir, o.record,
                                                           o.json_path, !o.no_record);
      !files) {
    std::fprintf(stderr, "mbzirc2017-run: %s\n", files.message().c_str());
    return 2;
  } else {
    o.run_dir = files->dir;
    o.record = files->video;
    o.json_path = files->summary;
  }
  Launcher launch("mbzirc2017-run", o.quiet);
  int harness_error = 0;
  auto fail = [&](const std::string& why) {
    std::fprintf(stderr, "mbzirc2017-run: %s\n", why.c_str());
    harness_error = 4;
  };
  std::string world = o.world;
  if (o.truck_speed_kmh > 0.0) {
    world = world_with_speed(o.world, o.truck_speed_kmh, o.seed);
    if (world.empty()) {
      fail("cannot write a world with the truck at " + std::to_string(o.truck_speed_kmh) + " km/h");
      return 4;
    }
  }

  // the ground truth the summary is scored from
  double takeoff_s = -1.0, landed_s = -1.0, relative_speed_m_s = -1.0, marker_distance_m = -1.0;
  double end_sim_s = 0.0;
  bool stayed_on_deck = false;
  std::vector<std::string> crashes, states;
  std::string vision_log;  // the UAV program's video log, in the run directory
  double first_blackout_s = -1.0, approach_blackout_s = -1.0;  // when the faults were injected

  uavsim::launch::ServerSpec spec;
  spec.path = o.server;
  spec.world = world;
  spec.extra_args = {"--seed", std::to_string(o.seed)};
  if (!o.record.empty()) {
    spec.extra_args.insert(spec.extra_args.end(), {"--record", o.record, "--record-camera", o.record_camera,
                                                   "--record-layout", o.record_layout});
  }
  if (!o.run_dir.empty()) {
    spec.extra_args.insert(spec.extra_args.end(), {"--log-dir", o.run_dir});
    launch.record_truth(o.run_dir, o.truth_hz);
  }
  if (!o.realism.empty()) spec.extra_args.insert(spec.extra_args.end(), {"--realism", o.realism});
  if (!o.wind.empty()) spec.extra_args.insert(spec.extra_args.end(), {"--wind", o.wind});
  if (auto started = launch.start_server(spec); !started) {
    fail(started.message());
  } else if (launch.mavlink_port("uav0") == 0) {
    fail("the server did not start (no MAVLink port for uav0)");
  }
  const bool faults = o.blackout_first_pass || o.lose_in_approach;
  std::vector<std::pair<std::int64_t, double>> ticks;  // the fault injector's ticks (number, time)
  std::vector<std::pair<double, std::string>>
      pending_states;  // from the UAV's output, not yet acted on
  if (!harness_error) {
    SimConnection& api = launch.api();
    // 1. hold the clock, start from t = 0 with this seed; the truck alone drives to the start time
    if (!api.pause() || !api.reset(o.seed) || !api.subscribe_events()) {
      fail("the server refused the setup requests (pause, reset, subscribe_events)");
    } else if (o.start_time_s > 0.0 &&
               !api.step_for(o.start_time_s, std::max(60.0, o.start_time_s))) {
      fail("the server did not run to the start time");
    } else if (!api.request({{"op", "pause_at"},
                             {"time_s", o.start_time_s + o.budget_s},
                             {"lockstep_empty", true}})) {
      // the clock stops by itself at the end (budget spent, the program gone, or 5 s on the deck):
      // the end of the run is the same every run
      fail("the server refused pause_at");
    }
    launch.on_line([&](const std::string& child, const std::string& line) {
      if (child != "uav0") return;
      if (auto s = state_change(line)) {
        states.push_back(s->second);
        pending_states.push_back(*s);
      }
    });
    // 2. the UAV program (and the fault injector) on the lockstep clock, then let the clock go
    if (!harness_error) {
      std::vector<std::string> argv{
          o.uav, "--mavlink", "tcp:127.0.0.1:" + std::to_string(launch.mavlink_port("uav0"))};
      if (!o.run_dir.empty()) {
        // what its vision saw, frame by frame (uavsim-videolog-export makes an MP4 of it)
        vision_log = o.run_dir + "/uav0_vision.vlog";
        argv.insert(argv.end(), {"--video-log", vision_log});
      }
      auto u = launch.spawn("uav0", argv, {launch.lockstep_env(kLockstepPeriod_s)});
      if (!u) fail(u.message());
    }
    if (!harness_error && faults) {
      api.on_message("tick", [&](const SimMessage& m) {
        ticks.emplace_back(m.json.value("tick", std::int64_t{0}), m.json.value("time", 0.0));
      });
      if (!api.lockstep_join(kLockstepPeriod_s, 120.0))
        fail("the fault injector could not join the lockstep");
    }
    if (!harness_error) {
      if (auto w = launch.wait_lockstep_clients(faults ? 2 : 1, 120.0); !w) {
        fail("the UAV program did not join the lockstep");
      } else if (!api.resume()) {
        fail("resume refused");
      } else {
        launch.say("mbzirc2017-run: seed " + std::to_string(o.seed) +
                   ", UAV starts at t=" + std::to_string(static_cast<int>(o.start_time_s)) +
                   " s, budget " + std::to_string(static_cast<int>(o.budget_s)) + " s sim");
      }
    }

    // 3. follow the program and the event stream until it has landed (and 5 s more), it gave up, or
    // the budget is spent
    double sim_s = o.start_time_s, last_status_wall_s = 0.0;
    while (!harness_error) {
      launch.pump(ticks.empty() ? 50 : 0);
      for (const SimMessage& m : api.take_messages()) {
        if (m.kind() != "sim_event") continue;
        const Json& e = m.json;
        const std::string type = e.value("type", ""), vehicle = e.value("vehicle_name", "");
        const std::string detail = e.value("detail", "");
        const double t = e.value("time", 0.0);
        if (type == "takeoff" && takeoff_s < 0) takeoff_s = t;
        if (type == "crash")
          crashes.push_back(vehicle + " at " + std::to_string(t) + " s: " + detail);
        if (type == "landed_on_target" && landed_s < 0) {
          landed_s = t;
          // the clock is then still short of t + 5 s (a few ms of wall time at full speed)
          const auto r = api.request({{"op", "pause_at"}, {"time_s", t + kStayOnDeck_s}});
          if (r && r->value("time_s", 0.0) > t + kStayOnDeck_s) {
            launch.say("mbzirc2017-run: the end-of-run pause came late (the run's end may vary)");
          }
          std::smatch mm;
          static const std::regex re(
              R"(relative speed ([0-9.]+) m/s, ([0-9.]+) m from the marker centre)");
          if (std::regex_search(detail, mm, re)) {
            relative_speed_m_s = std::stod(mm[1]);
            marker_distance_m = std::stod(mm[2]);
          }
        }
        if (type == "crash" || type == "takeoff" || type == "touchdown" ||
            type == "landed_on_target" || type == "disarmed") {
          char buf[320];
          std::snprintf(buf, sizeof(buf), "[event] t=%.2f %s %s %s", t, type.c_str(),
                        vehicle.c_str(), detail.c_str());
          launch.say(buf);
        }
      }
      // the fault injector: at each tick, act on the program's state changes stamped before it
      // (requests below may read further ticks into `ticks`: they wait for the next pass)
      const std::vector<std::pair<std::int64_t, double>> due = std::move(ticks);
      ticks.clear();
      for (const auto& [tick, tick_s] : due) {
        for (auto it = pending_states.begin(); it != pending_states.end();) {
          if (it->first >= tick_s - 1e-9) {
            ++it;
            continue;
          }
          const std::string state = it->second;
          it = pending_states.erase(it);
          double duration = 0.0;
          if (o.blackout_first_pass && state == "Intercept" && first_blackout_s < 0) {
            duration = kFirstPassBlackout_s;
            first_blackout_s = tick_s;
          } else if (o.lose_in_approach && state == "Approach" && approach_blackout_s < 0) {
            duration = kApproachBlackout_s;
            approach_blackout_s = tick_s;
          }
          if (duration > 0.0) {
            if (!api.request({{"op", "camera_blackout"},
                              {"camera", "uav0_down"},
                              {"duration_s", duration}})) {
              fail("camera_blackout refused");
            }
            char buf[160];
            std::snprintf(buf, sizeof(buf), "[fault] t=%.2f camera uav0_down black for %.0f s (%s)",
                          tick_s, duration, state.c_str());
            launch.say(buf);
          }
        }
        sim_s = tick_s;
        if (!api.done(tick)) fail("the fault injector's done was refused");
      }
      if (launch.wall_s() - last_status_wall_s > 0.5) {
        last_status_wall_s = launch.wall_s();
        if (const auto s = api.status(); s) {
          sim_s = s->value("time_s", sim_s);
          // the program exits 3 s after its landing and the clock holds then (pause_at): go on to
          // the 5 s on the deck, where the next armed pause holds it again
          if (landed_s >= 0 && s->value("paused", false) &&
              sim_s < landed_s + kStayOnDeck_s - kPauseSlack_s)
            (void)api.resume();
        }
      }
      // scored: still on the deck 5 s after touchdown
      if (landed_s >= 0 && sim_s >= landed_s + kStayOnDeck_s - kPauseSlack_s) break;
      if (launch.programs_done() && landed_s < 0) break;
      if (sim_s >= o.start_time_s + o.budget_s - kPauseSlack_s) {
        launch.say("mbzirc2017-run: sim-time budget spent");
        break;
      }
      if (launch.wall_s() > o.wall_limit_s) {
        launch.say("mbzirc2017-run: wall-clock limit reached");
        break;
      }
      if (launch.server_exited()) {
        fail("the server exited");
        break;
      }
    }
    if (faults) (void)api.lockstep_leave();
    // the clock holds by itself at the end (pause_at): score once it does
    for (const double until_s = launch.wall_s() + 10.0; !harness_error && launch.wall_s() < until_s;
         launch.pump(10)) {
      const auto st = api.status();
      if (!st || st->value("paused", false)) break;
    }
    if (!o.events_path.empty()) {
      if (const auto ev = api.request({{"op", "events"}}); ev) {
        std::ofstream f(o.events_path);
        for (const Json& e : ev->at("events")) f << e.dump() << "\n";
      }
    }

    // 4. score from ground truth
    if (const auto t = api.truck(); t) {
      end_sim_s = t->value("time_s", 0.0);
      for (const Json& truck : t->at("trucks")) {
        for (const Json& c : truck.value("carried_vehicles", Json::array()))
          stayed_on_deck = stayed_on_deck || c == 0;
      }
    }
    for (const SimMessage& m : api.take_messages()) {
      if (m.kind() == "sim_event" && m.json.value("type", "") == "crash") {
        crashes.push_back(m.json.value("vehicle_name", "") + ": " + m.json.value("detail", ""));
      }
    }
    stayed_on_deck =
        stayed_on_deck && landed_s >= 0 && end_sim_s >= landed_s + kStayOnDeck_s - kPauseSlack_s;
  }
  launch.stop_all(60.0);
  if (world != o.world) std::remove(world.c_str());

  const bool landed = landed_s >= 0;
  const bool success = harness_error == 0 && landed && stayed_on_deck && crashes.empty();
  const double mission_s = landed && takeoff_s >= 0 ? landed_s - takeoff_s : -1.0;
  std::printf("==== MBZIRC 2017 landing on the moving truck, seed %llu ====\n",
              static_cast<unsigned long long>(o.seed));
  std::printf(
      "landed on the deck: %s%s\n", landed ? "yes" : "no",
      landed ? (stayed_on_deck ? " (still on it 5 s later)" : " (NOT on it 5 s later)") : "");
  if (mission_s >= 0) {
    std::printf("take-off to touchdown: %.1f s sim (take-off t=%.1f s, touchdown t=%.1f s)\n",
                mission_s, takeoff_s, landed_s);
    std::printf("relative speed at touchdown: %.2f m/s; distance from the marker centre: %.2f m\n",
                relative_speed_m_s, marker_distance_m);
  } else {
    std::printf("take-off to touchdown: n/a\n");
  }
  std::printf("crashes: %s\n", crashes.empty() ? "none" : "");
  for (const std::string& c : crashes) std::printf("  %s\n", c.c_str());
  std::printf("sim time: %.1f s, wall time: %.1f s\n", end_sim_s, launch.wall_s());
  std::printf("video: %s\n", o.record.empty() ? "none" : o.record.c_str());
  if (!vision_log.empty()) {
    std::printf("vision log: %s (uavsim-videolog-export %s --mp4 FILE)\n", vision_log.c_str(),
                vision_log.c_str());
  }
  if (!o.run_dir.empty()) {
    std::printf("run directory: %s (%llu ground-truth rows; plots: scripts/plot_run.py %s)\n", o.run_dir.c_str(),
                static_cast<unsigned long long>(launch.truth_rows()), o.run_dir.c_str());
  }
  std::printf("RESULT: %s\n", success ? "SUCCESS" : "FAILURE");
  std::fflush(stdout);

  if (!o.json_path.empty()) {
    Json summary;
    summary["mission"] = "mbzirc2017";
    summary["run_dir"] = o.run_dir;
    summary["video"] = o.record;
    summary["vision_log"] = vision_log;
    summary["seed"] = o.seed;
    summary["truck_speed_kmh"] = o.truck_speed_kmh > 0.0 ? o.truck_speed_kmh : 15.0;
    summary["start_time_s"] = o.start_time_s;
    summary["landed"] = landed;
    summary["stayed_on_deck"] = stayed_on_deck;
    summary["takeoff_time_s"] = takeoff_s;
    summary["touchdown_time_s"] = landed_s;
    summary["mission_time_s"] = mission_s;
    summary["relative_speed_m_s"] = relative_speed_m_s;
    summary["marker_distance_m"] = marker_distance_m;
    summary["crashes"] = crashes;
    summary["states"] = states;
    summary["blackout_first_pass_at_s"] = first_blackout_s;
    summary["blackout_approach_at_s"] = approach_blackout_s;
    summary["sim_time_s"] = end_sim_s;
    summary["wall_time_s"] = launch.wall_s();
    summary["success"] = success;
    std::ofstream(o.json_path) << summary.dump(2) << "\n";
  }
  if (harness_error) return harness_error;
  return success ? 0 : 1;
}
