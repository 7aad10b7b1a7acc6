#include "funnel.hpp"

#include <algorithm>

namespace uavsim::missions::mbzirc2017 {

Funnel::Funnel(const MissionConfig& config) : config_(config) {}

double Funnel::radius_m(double height_m) const {
  const double h = std::max(height_m, 0.0);
  return std::min(config_.funnel_base_radius_m + config_.funnel_slope * h,
                  config_.funnel_max_radius_m);
}

bool Funnel::contains(double height_m, double offset_m) const {
  return offset_m <= radius_m(height_m);
}

double Funnel::descent_rate_m_s(double height_m) const {
  return std::clamp(config_.descent_min_m_s + config_.descent_per_m_1_s * std::max(height_m, 0.0),
                    config_.descent_min_m_s, config_.descent_max_m_s);
}

}  // namespace uavsim::missions::mbzirc2017
