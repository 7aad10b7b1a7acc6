// Range checks for numbers that come from outside (MAVLink fields, API fields, world attributes) before
// they reach a loop, a cast or an allocation. A double converted to an integer type out of range is
// undefined behaviour in C++ (and UBSan's float-cast-overflow), so every such conversion goes through
// checked_integer().
#pragma once

#include <cmath>
#include <concepts>
#include <limits>
#include <optional>

namespace uavsim::server::sim {

// True when v is finite and lo <= v <= hi.
inline bool finite_in(double v, double lo, double hi) { return std::isfinite(v) && v >= lo && v <= hi; }

// v as T when v is finite, a whole number and representable in T; nullopt otherwise. The bounds are
// compared as exact powers of two, so 2^32 is refused for uint32 (comparing with (double)UINT32_MAX would
// be exact too, but (double)UINT64_MAX rounds up to 2^64 and would let 2^64 through).
template <std::integral T>
std::optional<T> checked_integer(double v) {
  if (!std::isfinite(v) || v != std::trunc(v)) return std::nullopt;
  constexpr int kDigits = std::numeric_limits<T>::digits;  // value bits, without the sign
  const double upper = std::ldexp(1.0, kDigits);           // one past the largest value
  const double lower = std::numeric_limits<T>::is_signed ? -upper : 0.0;
  if (v < lower || v >= upper) return std::nullopt;
  return static_cast<T>(v);
}

// checked_integer() further limited to [lo, hi].
template <std::integral T>
std::optional<T> checked_integer(double v, T lo, T hi) {
  const std::optional<T> r = checked_integer<T>(v);
  if (!r || *r < lo || *r > hi) return std::nullopt;
  return r;
}

}  // namespace uavsim::server::sim
