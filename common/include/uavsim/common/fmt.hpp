// Up to three numbers printed into a std::string with a printf format, for the missions' log and
// status lines ("t=%.1f s"). The arguments are doubles, so an int argument is converted before it
// meets a %f (passing it through unconverted would be undefined). Output beyond 159 characters is
// cut. Thread-safe (pure).
#pragma once

#include <cstdio>
#include <string>

namespace uavsim::common {

inline std::string fmt(const char* format, double a, double b = 0.0, double c = 0.0) {
  char buf[160];
  std::snprintf(buf, sizeof buf, format, a, b, c);
  return buf;
}

}  // namespace uavsim::common
