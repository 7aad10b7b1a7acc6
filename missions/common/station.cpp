#include "uavsim/mission/station.hpp"

#include <cstdio>

namespace uavsim::mission {

std::optional<Station> start_station(const std::string& name, int uav_count,
                                     const client::GcsLinkConfig& config) {
  Station s;
  std::string error;
  s.links = client::open_station_links(uav_count, config, &error);
  if (s.links.empty()) {
    std::fprintf(stderr, "%s: %s\n", name.c_str(), error.c_str());
    return std::nullopt;
  }
  for (size_t i = 0; i < s.links.size(); ++i)
    std::printf("gcs: uav%zu link on udp:127.0.0.1:%u\n", i, s.links[i]->local_port());
  std::fflush(stdout);
  s.program = ProgramLoop::create(name);
  if (!s.program) return std::nullopt;
  return s;
}

}  // namespace uavsim::mission
