// MAVLink 1/2 framing constants and the decoded-frame view the Parser hands out.
// Layouts (MAVLink spec "Serialization"):
//   v1: 0xFE LEN SEQ SYSID COMPID MSGID                                   payload CRC(2)
//   v2: 0xFD LEN INCOMPAT COMPAT SEQ SYSID COMPID MSGID(3, little-endian)  payload CRC(2)
//   [signature(13)]
// The CRC covers the header after the start byte and the payload, then the message's CRC_EXTRA
// byte.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>

#include "uavsim/common/mavlink/generated/message_table.hpp"

namespace uavsim::common::mavlink {

enum class Version : std::uint8_t { kV1 = 1, kV2 = 2 };

inline constexpr std::uint8_t kStxV1 = 0xFE;
inline constexpr std::uint8_t kStxV2 = 0xFD;
inline constexpr std::size_t kHeaderLenV1 = 6;
inline constexpr std::size_t kHeaderLenV2 = 10;
inline constexpr std::size_t kChecksumLen = 2;
inline constexpr std::size_t kSignatureLen = 13;  // link id (1) + timestamp (6) + signature (6)
inline constexpr std::size_t kMaxPayloadLen = 255;
inline constexpr std::size_t kMaxFrameLen =
    kHeaderLenV2 + kMaxPayloadLen + kChecksumLen + kSignatureLen;
inline constexpr std::uint8_t kIncompatFlagSigned = 0x01;
// incompat flags this codec understands; a frame with any other bit set cannot be parsed safely
inline constexpr std::uint8_t kSupportedIncompatFlags = kIncompatFlagSigned;

using SecretKey = std::array<std::uint8_t, 32>;
using SignatureBytes = std::array<std::uint8_t, 6>;

// The 13-byte signature block of a signed MAVLink 2 frame.
struct Signature {
  std::uint8_t link_id = 0;
  std::uint64_t timestamp_10us = 0;  // 48 bits: units of 10 us since 2015-01-01 00:00:00 UTC
  SignatureBytes value{};            // first 6 bytes of the SHA-256 (see signing.hpp)
};

// One complete, checksum-verified frame.
struct Frame {
  Version version = Version::kV2;
  std::uint8_t incompat_flags = 0;  // always 0 for v1
  std::uint8_t compat_flags = 0;    // always 0 for v1
  std::uint8_t seq = 0;
  std::uint8_t sysid = 0;
  std::uint8_t compid = 0;
  std::uint32_t msgid = 0;
  std::uint8_t payload_len = 0;  // as sent; a v2 sender may have stripped trailing zeros
  // the payload, zero-filled from payload_len up to info->max_len, so
  // msg::X::decode(payload.data()) works
  std::array<std::uint8_t, kMaxPayloadLen> payload{};
  std::optional<Signature> signature;  // present iff the frame was signed
  const MessageInfo* info = nullptr;   // never null for a frame the Parser emits
  std::span<const std::uint8_t>
      raw;  // the frame's bytes as received; valid until the parser is fed again
};

}  // namespace uavsim::common::mavlink
