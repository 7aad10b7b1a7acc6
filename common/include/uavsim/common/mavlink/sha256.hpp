// SHA-256 (FIPS 180-4), small and allocation-free: MAVLink 2 signing needs it and nothing else here
// does.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

namespace uavsim::common::mavlink {

using Sha256Digest = std::array<std::uint8_t, 32>;

// Incremental hasher: update() any number of times, then finish() once. Not thread-safe (one per
// thread).
class Sha256 {
 public:
  Sha256();

  // Appends bytes to the message being hashed.
  void update(std::span<const std::uint8_t> bytes);

  // Pads the message and returns its digest; the hasher must not be used afterwards.
  Sha256Digest finish();

 private:
  void compress(const std::uint8_t* block);

  std::array<std::uint32_t, 8> state_;
  std::array<std::uint8_t, 64> block_{};
  std::size_t block_len_ = 0;
  std::uint64_t total_len_ = 0;  // bytes
};

// One-shot digest of a byte range. Thread-safe.
Sha256Digest sha256(std::span<const std::uint8_t> bytes);

}  // namespace uavsim::common::mavlink
