// Numbers given on a command line or in an environment variable, checked before anything uses them:
// the whole text must be the number (no trailing junk), finite, and inside the caller's range, so
// that a typo or a huge value becomes a usage error instead of a silent 0, an undefined cast or an
// endless loop. On failure the output is left as it was.
#pragma once

#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <type_traits>

namespace uavsim::common {

inline bool parse_double(const char* text, double lo, double hi, double* out) {
  if (text == nullptr || *text == '\0' || std::isspace(static_cast<unsigned char>(*text)))
    return false;
  char* end = nullptr;
  errno = 0;
  const double v = std::strtod(text, &end);
  if (end == text || *end != '\0' || errno == ERANGE || !std::isfinite(v) || v < lo || v > hi)
    return false;
  *out = v;
  return true;
}

// Decimal digits only (a leading '-' for signed types), within [lo, hi].
template <class Int>
bool parse_integer(const char* text, Int lo, Int hi, Int* out) {
  static_assert(std::is_integral_v<Int>);
  if (text == nullptr) return false;
  const bool negative = std::is_signed_v<Int> && *text == '-';
  if (!std::isdigit(static_cast<unsigned char>(text[negative ? 1 : 0]))) return false;
  char* end = nullptr;
  errno = 0;
  if constexpr (std::is_signed_v<Int>) {
    const long long v = std::strtoll(text, &end, 10);
    if (*end != '\0' || errno == ERANGE || v < static_cast<long long>(lo) ||
        v > static_cast<long long>(hi)) {
      return false;
    }
    *out = static_cast<Int>(v);
  } else {
    const unsigned long long v = std::strtoull(text, &end, 10);
    if (*end != '\0' || errno == ERANGE || v < static_cast<unsigned long long>(lo) ||
        v > static_cast<unsigned long long>(hi)) {
      return false;
    }
    *out = static_cast<Int>(v);
  }
  return true;
}

}  // namespace uavsim::common
