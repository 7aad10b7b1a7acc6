#include "uavsim/launch/run_options.hpp"

#include <cstdio>

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
