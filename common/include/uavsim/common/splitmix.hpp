// splitmix64's output function (Steele, Lea and Flood 2014): a fixed, fully specified mix of a
// 64-bit word, so that seeds, streams and indices that differ by one give unrelated bits, the
// same on every platform and standard library. The simulator's seeded draws (balloon placements,
// per-vehicle seeds, frame noise, radio entry offsets, a launcher's sampled runs) all go through
// it.
#pragma once

#include <cstdint>

namespace uavsim::common {

// The generator's increment (2^64 / golden ratio, odd): a splitmix64 stream is mix(state += it).
inline constexpr uint64_t kSplitMixGamma = 0x9E3779B97F4A7C15ull;

constexpr uint64_t splitmix64_mix(uint64_t z) {
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

}  // namespace uavsim::common
