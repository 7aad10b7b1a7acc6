// MAVLink 2 message signing (MAVLink spec "Message Signing"): the signature is the first 6 bytes of
// SHA-256(secret_key + header + payload + crc + link_id + timestamp), i.e. the key followed by
// every byte of the frame up to and including the 6-byte timestamp.
#pragma once

#include <cstdint>
#include <span>

#include "uavsim/common/mavlink/frame.hpp"

namespace uavsim::common::mavlink {

// 2015-01-01 00:00:00 UTC in Unix seconds: the epoch of signing timestamps.
inline constexpr std::uint64_t kSigningEpochUnixS = 1420070400;

// Computes the signature of a frame; signed_part is the frame from its start byte through the
// timestamp. Thread-safe.
SignatureBytes compute_signature(const SecretKey& key, std::span<const std::uint8_t> signed_part);

// Converts Unix time in microseconds to a signing timestamp (10 us units since 2015); 0 before
// 2015.
constexpr std::uint64_t signing_timestamp_from_unix_us(std::uint64_t unix_us) {
  constexpr std::uint64_t kEpochUs = kSigningEpochUnixS * 1000000;
  return unix_us > kEpochUs ? (unix_us - kEpochUs) / 10 : 0;
}

// Hands out strictly increasing signing timestamps for one outgoing link, as the spec requires even
// when several frames are sent within one 10 us tick or the clock steps back. Not thread-safe (one
// per link).
class TimestampSource {
 public:
  // Returns max(now_10us, previous + 1).
  std::uint64_t next(std::uint64_t now_10us) {
    last_10us_ = (now_10us > last_10us_) ? now_10us : last_10us_ + 1;
    return last_10us_;
  }

 private:
  std::uint64_t last_10us_ = 0;
};

}  // namespace uavsim::common::mavlink
