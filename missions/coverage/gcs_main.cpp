// coverage-gcs: the ground station of the coverage flock's optimised variant (the thesis the
// project descends from, section 3.6): one GCS link (seed 6.3) per UAV, each agent's APD united
// into the station's map (ground_station.hpp), the map sent back to every UAV at most every
// --map-period seconds when it changed. It prints the UDP port of each UAV's link, then its map as
// an `APD 255 ...` line (apd_report.hpp) when it changed (at most every --report-period seconds):
// the launcher scores data delivered here as surviving. Runs until stopped (SIGTERM) or
// --max-time seconds of loop time (the lockstep clock under UAVSIM_LOCKSTEP).
//
// usage: coverage-gcs --uavs N --area WxH [options]; --help lists them.
// Exit status: 0 at the end, 1 on a socket or clock failure, 2 usage.
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "apd_report.hpp"
#include "coverage_config.hpp"
#include "ground_station.hpp"
#include "station_link.hpp"
#include "uavsim/client/event_loop.hpp"
#include "uavsim/client/gcs_link.hpp"
#include "uavsim/common/parse_number.hpp"
#include "uavsim/mission/station.hpp"

using namespace uavsim::client;
using namespace uavsim::missions::coverage;
using uavsim::common::parse_double;

namespace {

constexpr double kStep_s = 0.05;

volatile std::sig_atomic_t g_stop = 0;
void on_signal(int) { g_stop = 1; }

int usage() {
  std::fprintf(stderr, R"(usage: coverage-gcs --uavs N --area WxH [options]
  --uavs N             one GCS link per UAV, 0..N-1 (1-64)
  --area WxH           the rectangle (as coverage-agent's), metres
  --sensor XxY         sensor footprint (default 7x10): sets the stripes, as the agents'
  --map-period S       the map goes to the UAVs at most every S seconds (default 2)
  --report-period S    the map's APD line at most every S seconds (default 1)
  --max-time S         stop after S seconds of loop time (default 36000)
)");
  return 2;
}

bool pair_of(const char* s, double* a, double* b) {
  char* e = nullptr;
  *a = std::strtod(s, &e);
  if (e == s || *e != 'x') return false;
  const char* s2 = e + 1;
  *b = std::strtod(s2, &e);
  return e != s2 && *e == '\0' && std::isfinite(*a) && std::isfinite(*b);
}

}  // namespace

int main(int argc, char** argv) {
  double uavs = 0, map_period_s = 2.0, report_period_s = 1.0, max_time_s = 36000.0;
  CoverageConfig config;
  bool have_area = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--help" || a == "-h" || i + 1 >= argc) return usage();
    const char* v = argv[++i];
    double x = 0, y = 0;
    if (a == "--uavs" && parse_double(v, 1, kMaxAgents, &uavs) && uavs == std::floor(uavs)) {
    } else if (a == "--area" && pair_of(v, &x, &y)) {
      config.length_x_m = x;
      config.width_y_m = y;
      have_area = true;
    } else if (a == "--sensor" && pair_of(v, &x, &y)) {
      config.x_sensor_m = x;
      config.y_sensor_m = y;
    } else if (a == "--map-period" && parse_double(v, 0.05, 3600, &map_period_s)) {
    } else if (a == "--report-period" && parse_double(v, 0.05, 3600, &report_period_s)) {
    } else if (a == "--max-time" && parse_double(v, 1, 1e7, &max_time_s)) {
    } else {
      return usage();
    }
  }
  if (uavs < 1 || !have_area) return usage();
  if (const std::string why = config.validate(); !why.empty()) {
    std::fprintf(stderr, "coverage-gcs: %s\n", why.c_str());
    return 2;
  }
  std::signal(SIGTERM, on_signal);
  std::signal(SIGINT, on_signal);

  // a link per UAV, each learning its UAV's address from the first packet (the UAVs call the GCS)
  std::optional<uavsim::mission::Station> gcs = uavsim::mission::start_station(
      "coverage-gcs", static_cast<int>(uavs), station_link_config(kGcsId));
  if (!gcs) return 1;
  const std::vector<std::unique_ptr<GcsLink>>& links = gcs->links;
  uavsim::mission::ProgramLoop& program = *gcs->program;
  EventLoop& loop = program.loop();
  auto now_us = [&program] { return program.now_us(); };

  // the links are read at the steps only (not as datagrams arrive), so that what is heard at a
  // step does not depend on the host's timing
  CoverageGroundStation station(config.stripe_count(), map_period_s);
  AreaParts reported(config.stripe_count());
  double last_report_s = -1e9;
  auto report = [&] {
    std::printf("%s\n", encode_apd_report(kGcsId, loop.now(), station.map()).c_str());
    std::fflush(stdout);
    reported = station.map();
    last_report_s = loop.now();
  };
  while (!g_stop && loop.now() < max_time_s) {
    if (auto r = loop.run_for(kStep_s); !r) {
      if (g_stop) break;
      std::fprintf(stderr, "coverage-gcs: clock: %s\n", r.message().c_str());
      return 1;
    }
    for (auto& l : links) {
      l->service(now_us());
      for (const GcsMessage& m : l->take_received()) {
        if (m.topic == kTopicAgentApd) (void)station.on_agent_apd(m.payload);
      }
    }
    if (auto map = station.poll_map(loop.now())) {
      for (auto& l : links) (void)l->publish(kTopicStationMap, *map);
    }
    if (!(station.map() == reported) && loop.now() - last_report_s >= report_period_s) report();
  }
  if (!(station.map() == reported)) report();
  std::printf("gcs t=%.2f stopped: %d APDs received, %.2f %% of the rectangle held\n", loop.now(),
              station.apds_received(), 100.0 * station.map().covered_fraction(config.width_y_m));
  std::fflush(stdout);
  return 0;
}
