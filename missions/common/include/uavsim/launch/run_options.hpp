// The options every mission launcher (mbzirc2017-run, mbzirc2020-run, coverage-run) takes alike,
// the server they ask for, and the checks that end any run's loop. A launcher's own Options derive
// from RunOptions and add the mission's.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "uavsim/launch/launcher.hpp"

namespace uavsim::launch {

struct RunOptions {
  uint64_t seed = 1;
  std::string world;   // the world file (--world)
  std::string server;  // the uavsim-server program (--server)
  // the video (--record; "" none) and how it is filmed: the server's --record-camera and
  // --record-layout ("" leaves the server's default)
  std::string record;
  std::string record_camera = "follow";
  std::string record_layout = "tiled";
  std::string run_dir = "auto";  // --run-dir: video, summary, events, logs, ground truth
  std::string json_path;         // --json: the summary
  std::string events_path;       // --events: the sim's event log, one JSON line per event
  std::string realism;           // the server's --realism ("": the world's)
  std::string wind;              // the server's --wind ("": the world's)
  double truth_hz = 10.0;        // ground truth rows per second in the run directory
  // --floor S: instead of the mission, its floor for S sim seconds (run_floor); 0: the mission
  double floor_s = 0.0;
  bool quiet = false;
};

// The launcher's defaults for o: the world models/worlds/WORLD_FILE and the uavsim-server program,
// an install's own (PREFIX/share/uavsim/models, PREFIX/bin) else the build's (built_models_dir,
// built_server). Thread-safe.
void default_world_and_server(RunOptions* o, const std::string& world_file,
                              const std::string& built_models_dir, const std::string& built_server);

// What parse_run_option made of an option.
enum class RunOptionParse {
  kNotCommon,  // not one of RunOptions': the launcher's own, or unknown
  kTaken,      // set into the options
  kBad,        // one of RunOptions', but its value is not usable (usage)
};

// The option `name` with its `value` into o when it is one the launchers share: --seed (a whole
// number), --world, --server, --record, --record-camera, --record-layout, --run-dir, --json,
// --events, --realism, --wind, --truth-hz (0.01 to 1000) and --floor (sim seconds, 0.1 to 1e6).
// The launchers' flags without a value (--quiet, --no-run-dir, --no-record) stay theirs.
// Thread-safe.
RunOptionParse parse_run_option(const std::string& name, const char* value, RunOptions* o);

// The run files (resolve_run_files) set into o: run_dir, record (the video) and json_path; false
// after "MISSION-run: why" on stderr when the run directory cannot be used. record false:
// --no-record. Thread-safe.
bool resolve_run_files(const std::string& mission, RunOptions* o, bool record);

// The server of a run: o's world, "--seed N", the mission's own arguments, then the video's
// (--record, --record-camera, --record-layout), the run directory as its --log-dir, --realism and
// --wind, each where given. Thread-safe.
ServerSpec run_server_spec(const RunOptions& o, const std::vector<std::string>& mission_args);

// Starts that server, with the ground truth recorded into the run directory if there is one.
// Owner thread only (launch's).
Result<void> start_run_server(Launcher& launch, const RunOptions& o,
                              const std::vector<std::string>& mission_args);

// The floor of a run (--floor S): the server this mission's run starts (run_server_spec(o,
// mission_args), with o's video and run directory if any), but with no mission program and no
// client: its vehicles take off and hover (--hover 10) and the cameras the mission's programs
// subscribe to (render_cameras, the server's --render-cameras list; "" none) are rendered and
// discarded, for o.floor_s sim seconds as fast as the server goes. A mission cannot be faster than
// its floor: mission wall time / floor wall time is what the mission's own programs and their
// traffic cost (bench/mission_floor.py runs both, alternated). Says "floor: sim time S s, wall
// time W s, speed Xx real time" (the server's own lines as the launcher prints them), and writes
// the summary (o.json_path, if any: "mission", "floor": true, floor_s, the server's report line as
// "server_report", sim_time_s and wall_time_s as a mission's). Returns the launcher's exit code:
// kExitSuccess once the server ran the whole span, kExitHarness if it did not start or ended
// otherwise, kExitInterrupted on SIGINT or SIGTERM. Owner thread only (launch's).
int run_floor(Launcher& launch, const std::string& mission, const RunOptions& o,
              const std::vector<std::string>& mission_args, const std::string& render_cameras);

// The usage lines of --floor, the same in every launcher's --help, their text from column
// text_column (the launcher's own option texts' column). Thread-safe.
std::string floor_usage(int text_column);

// Starts keeping the run's summary at o.json_path (Launcher::keep_summary), begun with the mission,
// the seed and the run directory. Owner thread only (launch's).
void keep_run_summary(Launcher& launch, const std::string& mission, const RunOptions& o);

// The checks every launcher's loop makes after its own: true when the run must end now, because
// the wall-clock limit is reached (said as "NAME: wall-clock limit reached"), the server has
// exited or the run's records cannot be written (those two are harness failures: *failure says
// why). Owner thread only (launch's).
bool run_must_end(Launcher& launch, const std::string& name, double wall_limit_s,
                  std::string* failure);

}  // namespace uavsim::launch
