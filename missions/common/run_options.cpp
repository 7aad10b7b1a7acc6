#include "uavsim/launch/run_options.hpp"

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "uavsim/common/install_paths.hpp"
#include "uavsim/common/parse_number.hpp"

namespace uavsim::launch {

namespace {

// --floor's range: a tenth of a second (a handful of control steps) to the server's own bound on
// --duration's order of magnitude (11 days of sim time)
constexpr double kMinFloor_s = 0.1;
constexpr double kMaxFloor_s = 1e6;

// The server's closing line: "uavsim-server: ran 43.600 s of sim time in 1.5 s of wall time ..."
constexpr const char* kServerReportPrefix = "uavsim-server: ran ";

}  // namespace

std::string floor_usage(int text_column) {
  const std::string option = "  --floor S";
  const std::string indent(static_cast<size_t>(std::max(text_column, 0)), ' ');
  const std::string first =
      option + std::string(static_cast<size_t>(
                               std::max<int>(1, text_column - static_cast<int>(option.size()))),
                           ' ');
  return first + "not the mission: its floor for S sim seconds (the same server, no program,\n" +
         indent +
         "the vehicles hovering, the mission's cameras rendered; bench/mission_floor.py\n" +
         indent + "compares the two)\n";
}

bool resolve_run_files(const std::string& mission, RunOptions* o, bool record) {
  const auto files =
      resolve_run_files(mission, o->seed, o->run_dir, o->record, o->json_path, record);
  if (!files) {
    std::fprintf(stderr, "%s-run: %s\n", mission.c_str(), files.message().c_str());
    return false;
  }
  o->run_dir = files->dir;
  o->record = files->video;
  o->json_path = files->summary;
  return true;
}

void default_world_and_server(RunOptions* o, const std::string& world_file,
                              const std::string& built_models_dir,
                              const std::string& built_server) {
  o->world = common::find_models_dir("", built_models_dir).path + "/worlds/" + world_file;
  o->server = common::installed_or_built_program("uavsim-server", built_server);
}

RunOptionParse parse_run_option(const std::string& name, const char* value, RunOptions* o) {
  // the options given as text
  const std::pair<const char*, std::string*> texts[] = {
      {"--world", &o->world},
      {"--server", &o->server},
      {"--record", &o->record},
      {"--record-camera", &o->record_camera},
      {"--record-layout", &o->record_layout},
      {"--run-dir", &o->run_dir},
      {"--json", &o->json_path},
      {"--events", &o->events_path},
      {"--realism", &o->realism},
      {"--wind", &o->wind},
  };
  for (const auto& [option, field] : texts) {
    if (name == option) {
      *field = value;
      return RunOptionParse::kTaken;
    }
  }
  // and as numbers
  bool ok = true;
  if (name == "--seed")
    ok = common::parse_integer<std::uint64_t>(value, 0, UINT64_MAX, &o->seed);
  else if (name == "--truth-hz")
    ok = common::parse_double(value, 0.01, 1000.0, &o->truth_hz);
  else if (name == "--floor")
    ok = common::parse_double(value, kMinFloor_s, kMaxFloor_s, &o->floor_s);
  else
    return RunOptionParse::kNotCommon;
  return ok ? RunOptionParse::kTaken : RunOptionParse::kBad;
}

ServerSpec run_server_spec(const RunOptions& o, const std::vector<std::string>& mission_args) {
  ServerSpec spec;
  spec.path = o.server;
  spec.world = o.world;
  std::vector<std::string>& a = spec.extra_args;
  a = {"--seed", std::to_string(o.seed)};
  a.insert(a.end(), mission_args.begin(), mission_args.end());
  if (!o.record.empty()) {
    a.insert(a.end(), {"--record", o.record, "--record-camera", o.record_camera});
    if (!o.record_layout.empty()) a.insert(a.end(), {"--record-layout", o.record_layout});
  }
  if (!o.run_dir.empty()) a.insert(a.end(), {"--log-dir", o.run_dir});
  if (!o.realism.empty()) a.insert(a.end(), {"--realism", o.realism});
  if (!o.wind.empty()) a.insert(a.end(), {"--wind", o.wind});
  return spec;
}

Result<void> start_run_server(Launcher& launch, const RunOptions& o,
                              const std::vector<std::string>& mission_args) {
  if (!o.run_dir.empty()) launch.record_truth(o.run_dir, o.truth_hz);
  return launch.start_server(run_server_spec(o, mission_args));
}

int run_floor(Launcher& launch, const std::string& mission, const RunOptions& o,
              const std::vector<std::string>& mission_args, const std::string& render_cameras) {
  ServerSpec spec = run_server_spec(o, mission_args);
  char duration[32];
  std::snprintf(duration, sizeof(duration), "%.3f", o.floor_s);
  // the clock held until the launcher's API connection is in: a short floor would otherwise be
  // over before start_server() connects
  spec.extra_args.insert(spec.extra_args.end(),
                         {"--hover", "10", "--duration", duration, "--wait-for-clients", "1"});
  if (!render_cameras.empty())
    spec.extra_args.insert(spec.extra_args.end(), {"--render-cameras", render_cameras});
  std::string report;
  launch.on_line([&](const std::string& child, const std::string& line) {
    if (child != "server" || line.rfind(kServerReportPrefix, 0) != 0) return;
    report = line;
    launch.note_sim_time(o.floor_s);  // its end is then stamped at the span's end
  });
  bool harness_failed = false;
  std::string failure;
  if (auto started = launch.start_server(spec); !started) {
    harness_failed = true;
    failure = "the server did not start: " + started.message();
  } else {
    while (!launch.server_exited() && interrupted() == 0) launch.pump(100);
  }
  const double wall_s = launch.wall_s();
  launch.stop_all(30.0);
  const std::optional<ProgramEnd> end = launch.ended("server");
  if (!harness_failed && (report.empty() || !end || end->abnormal())) {
    harness_failed = true;
    failure = "the server did not run the whole span: " + launch.server_end();
  }
  if (harness_failed) std::fprintf(stderr, "floor: %s\n", failure.c_str());
  std::printf("floor: sim time %.1f s, wall time %.2f s, speed %.1fx real time\n", o.floor_s,
              wall_s, wall_s > 0.0 ? o.floor_s / wall_s : 0.0);
  std::fflush(stdout);
  const bool success = !harness_failed && interrupted() == 0;
  if (!o.json_path.empty()) {
    nlohmann::json summary = {{"mission", mission},      {"floor", true},
                              {"floor_s", o.floor_s},    {"render_cameras", render_cameras},
                              {"server_report", report}, {"sim_time_s", success ? o.floor_s : -1.0},
                              {"wall_time_s", wall_s},   {"success", success},
                              {"seed", o.seed}};
    if (!launch.write_summary(o.json_path, summary)) harness_failed = true;
  }
  return run_exit_code(harness_failed, success);
}

void keep_run_summary(Launcher& launch, const std::string& mission, const RunOptions& o) {
  launch.keep_summary(o.json_path,
                      {{"mission", mission}, {"seed", o.seed}, {"run_dir", o.run_dir}});
}

bool run_must_end(Launcher& launch, const std::string& name, double wall_limit_s,
                  std::string* failure) {
  if (launch.wall_s() > wall_limit_s) {
    launch.say(name + ": wall-clock limit reached");
    return true;
  }
  if (launch.server_exited()) {
    *failure = launch.server_end();
    return true;
  }
  if (!launch.records_error().empty()) {
    *failure = "the run's records cannot be written: " + launch.records_error();
    return true;
  }
  return false;
}

}  // namespace uavsim::launch
