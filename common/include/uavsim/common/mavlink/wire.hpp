// Little-endian field access for MAVLink payloads. Generated message code uses put/get; the string
// helpers are for the fixed-size char arrays (param ids, status text) that are not NUL-terminated
// when full.
#pragma once

#include <algorithm>
#include <array>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string_view>

namespace uavsim::common::mavlink::wire {

// MAVLink is little-endian; memcpy of native values is only correct on little-endian hosts.
static_assert(std::endian::native == std::endian::little,
              "MAVLink wire helpers assume a little-endian host");

template <class T>
inline void put(std::uint8_t* p, const T& value) {
  std::memcpy(p, &value, sizeof(T));
}

template <class T>
inline void get(const std::uint8_t* p, T& value) {
  std::memcpy(&value, p, sizeof(T));
}

}  // namespace uavsim::common::mavlink::wire

namespace uavsim::common::mavlink {

// Copies text into a MAVLink char array, NUL-padding the rest; text longer than N is cut to N
// chars.
template <std::size_t N>
void set_string(std::array<char, N>& field, std::string_view text) {
  field.fill('\0');
  std::copy_n(text.data(), std::min(text.size(), N), field.data());
}

// Reads a MAVLink char array up to its first NUL, or all N chars when it has none.
template <std::size_t N>
std::string_view get_string(const std::array<char, N>& field) {
  const auto* end = std::find(field.data(), field.data() + N, '\0');
  return std::string_view(field.data(), static_cast<std::size_t>(end - field.data()));
}

}  // namespace uavsim::common::mavlink
