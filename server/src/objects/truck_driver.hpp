// The person driving the MBZIRC 2017 truck (seed 7.1: "a moving ground vehicle, driven by a human
// operator"): a smooth, seeded wander across the ideal eight (lateral offset) and a wobble of the
// speed around the schedule, so that a mission's filter and controller meet a driver, not a train
// on rails. Each is a sum of three sinusoids with seeded periods, phases and weights; the weights
// sum to one, so |lateral| <= lateral_amplitude_m and |speed / scheduled speed - 1| <= speed_wobble
// at all times, and every derivative is bounded (no steps). Pure functions of sim time: the same
// seed gives the same drive, and a reset replays it.
//
// World numeric (any prefix; absent or zeros: the truck follows the ideal track exactly):
//   <numeric name="uavsim:NAME:driver" data="lateral_amplitude_m speed_wobble_fraction"/>
#pragma once

#include <array>
#include <cstdint>
#include <string>

#include "objects/eight_track.hpp"

namespace uavsim::server::objects {

struct DriverParams {
  double lateral_amplitude_m = 0.0;  // bound of the offset from the ideal path, [0, 2]
  double speed_wobble = 0.0;         // bound of the relative speed error, [0, 0.5)
};

// Empty if usable, else what is wrong (for startup errors).
std::string validate(const DriverParams& params);

// Immutable after construction; every method is const and thread-safe.
class TruckDriver {
 public:
  TruckDriver() = default;
  // params must pass validate(); salt separates trucks that share a seed.
  TruckDriver(const DriverParams& params, uint64_t seed, const std::string& salt);

  bool enabled() const { return params_.lateral_amplitude_m > 0.0 || params_.speed_wobble > 0.0; }
  const DriverParams& params() const { return params_; }

  // Arc length driven (unwrapped) and speed at sim time t, on the given schedule.
  double arc_length_m(const SpeedProfile& schedule, double time_s) const;
  double speed_m_s(const SpeedProfile& schedule, double time_s) const;
  // Offset to the left of the ideal path (m) and its rate (m/s).
  double lateral_m(double time_s) const;
  double lateral_rate_m_s(double time_s) const;

 private:
  struct Wave {
    double amplitude = 0.0;
    double omega_rad_s = 1.0;
    double phase_rad = 0.0;
  };
  using Waves = std::array<Wave, 3>;
  // sum of the waves, and its integral from 0 to t
  static double sum(const Waves& w, double time_s);
  static double integral(const Waves& w, double time_s);

  DriverParams params_;
  Waves lateral_{};
  Waves wobble_{};
};

}  // namespace uavsim::server::objects
