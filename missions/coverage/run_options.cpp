#include "run_options.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "agent.hpp"
#include "uavsim/common/install_paths.hpp"
#include "uavsim/common/parse_number.hpp"

namespace uavsim::missions::coverage {
using common::parse_double;

CoverageRunOptions::CoverageRunOptions() {
  // an install's own server and models (PREFIX/bin, PREFIX/share/uavsim/models), else the build's
  server = common::installed_or_built_program("uavsim-server", UAVSIM_SERVER_PATH);
  models_dir = common::find_models_dir("", UAVSIM_MODELS_DIR).path;
  record_camera = "overview";  // the whole rectangle
  record_layout = "";          // the server's own
}

// the command line into o; false: not usable (usage)
bool parse_run_options(int argc, char** argv, CoverageRunOptions* o) {
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    double v = 0, w = 0;
    if (a == "--quiet") {
      o->quiet = true;
      continue;
    }
    if (a == "--gcs") {
      o->gcs = true;
      continue;
    }
    if (a == "--pipelined") {
      o->pipelined = true;
      continue;
    }
    if (a == "--thesis-flocking") {
      o->thesis_flocking = true;
      continue;
    }
    if (a == "--no-record" || a == "--no-run-dir") {
      if (a == "--no-record") o->no_record = true;
      if (a == "--no-run-dir") o->run_dir = "none";
      continue;
    }
    if (a == "--help" || a == "-h" || i + 1 >= argc) return false;
    const char* val = argv[++i];
    if (a == "--agents" && parse_double(val, 1, kMaxAgents, &v) && v == std::floor(v)) {
      o->agents = static_cast<int>(v);
    } else if (a == "--area") {
      const char* x = std::strchr(val, 'x');
      if (x == nullptr || !parse_double(std::string(val, x).c_str(), 10, 3000, &v) ||
          !parse_double(x + 1, 10, 3000, &w))
        return false;
      o->length_x_m = v;
      o->width_y_m = w;
    } else if (a == "--failure-prob" && parse_double(val, 0, 1, &v)) {
      o->failure_prob = v;
    } else if (a == "--seed" && parse_double(val, 0, 1e15, &v) && v == std::floor(v)) {
      o->seed = static_cast<uint64_t>(v);
    } else if (a == "--kill") {
      const char* at = std::strchr(val, '@');
      if (at == nullptr || !parse_double(std::string(val, at).c_str(), 0, kMaxAgents - 1, &v) ||
          v != std::floor(v) || !parse_double(at + 1, 0, 1e6, &w))
        return false;
      o->kills.emplace_back(w, static_cast<int>(v));
    } else if (a == "--radio-range" && parse_double(val, 1, 10000, &v)) {
      o->radio_range_m = v;
    } else if (a == "--line-spacing" && parse_double(val, 3, 100, &v)) {
      o->line_spacing_m = v;
    } else if (a == "--radio-loss" && parse_double(val, 0, 1, &v)) {
      o->radio_loss = v;
    } else if (a == "--radio-backend" &&
               (std::strcmp(val, "simple") == 0 || std::strcmp(val, "ns3") == 0)) {
      o->radio_backend = val;
    } else if (a == "--radio-technology" &&
               (std::strcmp(val, "802.15.4") == 0 || std::strcmp(val, "802.11") == 0)) {
      o->radio_technology = val;
    } else if (a == "--radio-send-spread" && parse_double(val, 0, 1, &v)) {
      o->radio_send_spread_s = v;
    } else if (a == "--radio-tdma" && parse_double(val, 0.001, 1, &v)) {
      // the server checks the rest (a slot holds a frame; the vehicles' slots fit in the period)
      o->radio_tdma_slot_s = v;
    } else if (a == "--gcs-cut" && parse_double(val, 0, 1e6, &v)) {
      o->gcs_cut_s = v;
    } else if (a == "--gcs-loss" && parse_double(val, 0, 1, &v)) {
      o->gcs_loss = v;
    } else if (a == "--per-process" && parse_double(val, 1, kMaxAgents, &v) && v == std::floor(v)) {
      o->per_process = static_cast<int>(v);
    } else if (a == "--budget" && parse_double(val, 1, 1e6, &v)) {
      o->budget_s = v;
    } else if (a == "--wall-limit" && parse_double(val, 1, 1e6, &v)) {
      o->wall_limit_s = v;
    } else if (a == "--progress" && parse_double(val, 1, 1e6, &v)) {
      o->progress_period_s = v;
    } else if (a == "--agent-status" && parse_double(val, 0, 3600, &v)) {
      o->agent_status_s = v;
    } else if (a == "--json") {
      o->json_path = val;
    } else if (a == "--run-dir") {
      o->run_dir = val;
    } else if (a == "--record") {
      o->record = val;
    } else if (a == "--record-camera") {
      o->record_camera = val;
    } else if (a == "--truth-hz" && parse_double(val, 0.01, 1000, &v)) {
      o->truth_hz = v;
    } else if (a == "--map" && std::strchr(val, '\'') == nullptr) {
      o->map_png = val;
    } else if (a == "--world-out") {
      o->keep_world = val;
    } else if (a == "--server") {
      o->server = val;
    } else if (a == "--agent") {
      o->agent = val;
    } else if (a == "--gcs-program") {
      o->gcs_program = val;
    } else if (a == "--models-dir") {
      o->models_dir = val;
    } else if (a == "--floor") {  // the launchers' shared option (its range is theirs)
      if (uavsim::launch::parse_run_option(a, val, o) != uavsim::launch::RunOptionParse::kTaken)
        return false;
    } else {
      return false;
    }
  }
  return true;
}

// the checks between the options (after the run files are resolved); false after saying why
bool run_options_agree(const CoverageRunOptions& o) {
  if (!o.gcs && (o.gcs_cut_s >= 0.0 || o.gcs_loss > 0.0)) {
    std::fprintf(stderr, "coverage-run: --gcs-cut and --gcs-loss need --gcs\n");
    return false;
  }
  if (o.radio_technology != "802.15.4" && o.radio_backend != "ns3") {
    std::fprintf(stderr, "coverage-run: --radio-technology %s needs --radio-backend ns3\n",
                 o.radio_technology.c_str());
    return false;
  }
  if (o.radio_send_spread_s >= 0.0 && (o.radio_backend != "ns3" || o.radio_tdma_slot_s > 0.0)) {
    std::fprintf(stderr, "coverage-run: --radio-send-spread needs --radio-backend ns3, no TDMA\n");
    return false;
  }
  for (const auto& [t, id] : o.kills) {
    if (id >= o.agents) {
      std::fprintf(stderr, "coverage-run: --kill names agent %d of %d\n", id, o.agents);
      return false;
    }
  }
  return true;
}

}  // namespace uavsim::missions::coverage
