// Angle helpers: the one implementation of pi, of degrees to radians and back, and of wrapping to
// (-pi, pi], for the flight controller, the MAVLink frames, the client and the missions
// (header-only).
#pragma once

#include <cmath>

namespace uavsim::common {

inline constexpr double kPi = 3.14159265358979323846;
// multiply degrees by kDegToRad for radians, radians by kRadToDeg for degrees
inline constexpr double kDegToRad = kPi / 180.0;
inline constexpr double kRadToDeg = 180.0 / kPi;

// An angle in (-pi, pi], in O(1) for any input: std::remainder is exact, so small excursions come back
// exactly as a subtract-2pi loop would give them, and 1e30 costs no more than 1. A non-finite angle has no
// direction; it maps to 0 so that a NaN or inf can never reach a controller through this function (the
// MAVLink and API edges reject such values before, this is the last line).
inline double wrap_pi(double a_rad) {
  if (!std::isfinite(a_rad)) return 0.0;
  const double r = std::remainder(a_rad, 2.0 * kPi);
  return r <= -kPi ? r + 2.0 * kPi : r;
}

}  // namespace uavsim::common
