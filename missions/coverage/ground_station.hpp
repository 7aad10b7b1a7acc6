// The ground station of the optimised variant (the thesis the project descends from, section 3.6):
// every agent sends what it acquired to the ground control station on a best-effort link (the
// GCS link of client_cpp, seed 6.3); the station unites the maps it received and periodically
// sends its map back to every agent, in the same form as an APD. The leader merges the latest map
// into the result of its aggregation query before it plans, so data that reached the station
// before its agent failed is not flown again. The flock never waits for the station: without it,
// or with its link cut, the leader plans from the query alone (the plain variant). Pure: no
// sockets, no clocks.
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include "area_parts.hpp"

namespace uavsim::missions::coverage {

// GCS link topics (latest only: a newer map supersedes an unsent older one, which is never worth
// retransmitting)
inline constexpr uint16_t kTopicAgentApd = 0x8001;    // agent -> station: the agent's whole APD
inline constexpr uint16_t kTopicStationMap = 0x8002;  // station -> agents: the station's map

class CoverageGroundStation {
 public:
  // stripes > 0; the map goes out at most every map_period_s (> 0) seconds, when it changed.
  CoverageGroundStation(int stripes, double map_period_s);

  // An agent's APD (kTopicAgentApd payload) arrived: united into the map. False (nothing changes)
  // when the payload is malformed or is for another stripe count.
  bool on_agent_apd(const std::vector<uint8_t>& payload);
  // The map to send to every agent now (kTopicStationMap payload), when it changed since it was
  // last sent and the period has passed; nothing otherwise.
  std::optional<std::vector<uint8_t>> poll_map(double now_s);

  // Everything received so far.
  const AreaParts& map() const { return map_; }
  int apds_received() const { return apds_received_; }

 private:
  AreaParts map_;
  double map_period_s_;
  double next_map_s_ = 0.0;
  bool changed_ = false;
  int apds_received_ = 0;
};

}  // namespace uavsim::missions::coverage
