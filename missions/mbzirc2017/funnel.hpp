// The funnel-shaped safe descent volume of seed fig. 7.7: above the marker, a cone that widens with
// height. While the UAV is inside it, it descends; outside, it climbs for safety. Pure.
#pragma once

#include "mission_config.hpp"

namespace uavsim::missions::mbzirc2017 {

class Funnel {
 public:
  explicit Funnel(const MissionConfig& config);

  // The allowed horizontal distance from the marker's centre at height_m above the deck.
  double radius_m(double height_m) const;
  // Whether a UAV at height_m above the deck, offset_m horizontally from the marker, is inside.
  bool contains(double height_m, double offset_m) const;
  // The descent rate there (m/s, positive down): slow near the deck, faster high up.
  double descent_rate_m_s(double height_m) const;

 private:
  MissionConfig config_;
};

}  // namespace uavsim::missions::mbzirc2017
