// MAVLink's checksum: CRC-16/MCRF4XX ("X.25" in the MAVLink docs), init 0xFFFF, reflected
// polynomial 0x8408, no final xor. Table-driven (one lookup per byte); the table is built at
// compile time from the bitwise rule.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

namespace uavsim::common::mavlink {

inline constexpr std::uint16_t kCrcInit = 0xFFFF;

// Bitwise form of the MAVLink reference crc_accumulate(): the definition the table is checked
// against.
constexpr std::uint16_t crc_accumulate_bitwise(std::uint8_t byte, std::uint16_t crc) {
  std::uint8_t tmp = static_cast<std::uint8_t>(byte ^ (crc & 0xFF));
  tmp = static_cast<std::uint8_t>(tmp ^ (tmp << 4));
  return static_cast<std::uint16_t>((crc >> 8) ^ (tmp << 8) ^ (tmp << 3) ^ (tmp >> 4));
}

namespace detail {
constexpr std::array<std::uint16_t, 256> make_crc_table() {
  std::array<std::uint16_t, 256> table{};
  // with crc = i and input byte 0, one step of the bitwise rule is exactly the table entry for i
  for (unsigned i = 0; i < 256; ++i)
    table[i] = crc_accumulate_bitwise(0, static_cast<std::uint16_t>(i));
  return table;
}
inline constexpr std::array<std::uint16_t, 256> kCrcTable = make_crc_table();
}  // namespace detail

// Folds one byte into the running checksum.
constexpr std::uint16_t crc_accumulate(std::uint8_t byte, std::uint16_t crc) {
  return static_cast<std::uint16_t>((crc >> 8) ^ detail::kCrcTable[(crc ^ byte) & 0xFF]);
}

// Folds a byte range into the running checksum.
constexpr std::uint16_t crc_accumulate(std::span<const std::uint8_t> bytes, std::uint16_t crc) {
  for (std::uint8_t b : bytes) crc = crc_accumulate(b, crc);
  return crc;
}

}  // namespace uavsim::common::mavlink
