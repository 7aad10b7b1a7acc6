// What a mission's ground-station program (mbzirc2020-gcs, coverage-gcs) sets up first: one GCS
// link per UAV on loopback ephemeral ports, each learning its UAV's address from the first packet
// (the UAVs call the station), announced on stdout as "gcs: uavN link on udp:127.0.0.1:PORT" (the
// launchers read the ports there and put the server's relay in front of them), then its loop.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "uavsim/client/gcs_link.hpp"
#include "uavsim/mission/program.hpp"

namespace uavsim::mission {

struct Station {
  std::vector<std::unique_ptr<client::GcsLink>> links;  // index: the UAV's
  std::unique_ptr<ProgramLoop> program;
};

// The links and the loop of the station program `name`; nullopt after "NAME: why" on stderr.
// Loop thread only (the calling thread becomes it).
std::optional<Station> start_station(const std::string& name, int uav_count,
                                     const client::GcsLinkConfig& config);

}  // namespace uavsim::mission
