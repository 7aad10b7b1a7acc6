#include "ground_station.hpp"

#include <algorithm>

#include "radio_messages.hpp"

namespace uavsim::missions::coverage {

CoverageGroundStation::CoverageGroundStation(int stripes, double map_period_s)
    : map_(stripes), map_period_s_(map_period_s) {}

bool CoverageGroundStation::on_agent_apd(const std::vector<uint8_t>& payload) {
  const auto apd = decode_apd(payload, map_.stripe_count());
  if (!apd) return false;
  ++apds_received_;
  const AreaParts before = map_;
  map_.merge(*apd);
  changed_ = changed_ || !(map_ == before);
  return true;
}

std::optional<std::vector<uint8_t>> CoverageGroundStation::poll_map(double now_s) {
  if (!changed_ || now_s < next_map_s_) return std::nullopt;
  changed_ = false;
  next_map_s_ = now_s + map_period_s_;
  return encode_apd(map_);
}

}  // namespace uavsim::missions::coverage
