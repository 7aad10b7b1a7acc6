// Scaled integers of MAVLink fields, converted in one place: degrees as 1e-7 degree integers (the
// *_INT messages' lat/lon) and millimetres. Library internal; pure.
#pragma once

#include <cmath>
#include <cstdint>

namespace uavsim::client {

inline std::int32_t deg_e7(double deg) {
  return static_cast<std::int32_t>(std::llround(deg * 1e7));
}
inline double deg_from_e7(std::int32_t e7) { return e7 / 1e7; }
inline double m_from_mm(std::int32_t mm) { return mm / 1000.0; }

}  // namespace uavsim::client
