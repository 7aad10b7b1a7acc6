// mbzirc2020-gcs: the ground station of the balloon mission (seed 7.2): one GCS link (seed 6.3) per
// UAV, the allocator and supervisor of ground_station.hpp stepped at 20 Hz. It prints the UDP port
// of each UAV's link, then runs until every UAV has landed or is out (or --max-time s of loop
// time).
//
// usage: mbzirc2020-gcs [--uavs N] [--max-time S]
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "ground_station.hpp"
#include "messages.hpp"
#include "uavsim/client/event_loop.hpp"
#include "uavsim/client/gcs_link.hpp"
#include "uavsim/common/parse_number.hpp"
#include "uavsim/mission/station.hpp"

using namespace uavsim::client;
using namespace uavsim::missions::mbzirc2020;

namespace {
constexpr const char* kUsage = "usage: mbzirc2020-gcs [--uavs N] [--max-time S]\n";
}  // namespace

int main(int argc, char** argv) {
  int uav_count = 2;
  double max_time_s = 3600.0;
  for (int i = 1; i < argc; i += 2) {
    const std::string a = argv[i];
    if (a == "--help" || a == "-h") {
      std::fputs(kUsage, stdout);
      return 0;
    }
    bool ok = i + 1 < argc;  // every option takes a value: a lone one is not skipped
    if (ok && a == "--uavs")
      ok = uavsim::common::parse_integer(argv[i + 1], 1, 254, &uav_count);
    else if (ok && a == "--max-time")
      ok = uavsim::common::parse_double(argv[i + 1], 1.0, 1e6, &max_time_s);
    else
      ok = false;
    if (!ok) {
      std::fputs(kUsage, stderr);
      return 2;
    }
  }

  // a link per UAV, each learning its UAV's address from the first packet (the UAVs call the GCS)
  std::optional<uavsim::mission::Station> station =
      uavsim::mission::start_station("gcs", uav_count, GcsLinkConfig{kGcsId});
  if (!station) return 1;
  const std::vector<std::unique_ptr<GcsLink>>& links = station->links;
  uavsim::mission::ProgramLoop& program = *station->program;
  EventLoop& loop = program.loop();
  auto now_us = [&program] { return program.now_us(); };
  for (auto& l : links) {
    GcsLink* p = l.get();
    (void)loop.watch_fd(p->fd(), EventLoop::kReadable,
                        [p, &now_us](uint32_t) { p->service(now_us()); });
  }

  GroundStation gs(GroundStationConfig{}, uav_count);
  double finished_s = -1.0;
  while (loop.now() < max_time_s && (finished_s < 0 || loop.now() < finished_s + 1.0)) {
    if (auto r = loop.run_for(0.05); !r) {
      std::fprintf(stderr, "gcs: clock: %s\n", r.message().c_str());
      return 1;
    }
    const double now = loop.now();
    for (int i = 0; i < uav_count; ++i) {
      links[static_cast<size_t>(i)]->service(now_us());
      for (const GcsMessage& m : links[static_cast<size_t>(i)]->take_received()) {
        if (m.topic == kTopicStatus) {
          if (auto s = decode_status(m.payload)) gs.on_status(i, *s, now);
        } else if (m.topic == kTopicAirspace) {
          if (auto a = decode_airspace(m.payload)) gs.on_airspace(i, *a, now);
        } else if (m.topic == kTopicPopped) {
          if (auto p = decode_point(m.payload)) gs.on_popped(i, *p, now);
        }
      }
    }
    std::vector<std::string> notes;
    for (const GcsOutgoing& o : gs.step(now, &notes))
      links[static_cast<size_t>(o.uav)]->publish(o.topic, o.payload);
    for (const std::string& n : notes) std::printf("gcs t=%.2f %s\n", now, n.c_str());
    if (!notes.empty()) std::fflush(stdout);
    if (finished_s < 0 && gs.finished()) {
      finished_s = now;
      std::printf("gcs t=%.2f every UAV landed or out; %d balloon(s) reported popped\n", now,
                  gs.popped_reported());
      std::fflush(stdout);
    }
  }
  for (auto& l : links) loop.unwatch_fd(l->fd());
  return gs.finished() ? 0 : 3;
}
