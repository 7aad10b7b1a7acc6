#include "uavsim/launch/run_options.hpp"

#include <cstdint>
#include <cstdio>
#include <utility>

#include "uavsim/common/install_paths.hpp"
#include "uavsim/common/parse_number.hpp"

namespace uavsim::launch {

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
