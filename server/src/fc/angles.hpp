// Angle helpers shared by the flight-controller modules.
#pragma once

namespace uavsim::server::fc {

inline constexpr double kPi = 3.14159265358979323846;

// An angle in (-pi, pi]; the loops stay exact for the small excursions the controllers produce.
inline double wrap_pi(double a) {
  while (a > kPi) a -= 2.0 * kPi;
  while (a < -kPi) a += 2.0 * kPi;
  return a;
}

}  // namespace uavsim::server::fc
