// Standard base64 (RFC 4648 section 4), as the sim API carries radio frames ("data_b64"): the
// server and the client encode and decode with these two functions.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace uavsim::common {

// Always padded to a multiple of four characters.
std::string base64_encode(const std::uint8_t* bytes, std::size_t size);
inline std::string base64_encode(const std::vector<std::uint8_t>& bytes) {
  return base64_encode(bytes.data(), bytes.size());
}

// Strict: padding is optional, but nullopt for a character outside the alphabet, padding anywhere
// but the end (or more than two), an impossible length, or non-zero unused bits in the last
// character (a non-canonical encoding). Strict because a frame that decodes two ways is a bug to
// report, not to guess at.
std::optional<std::vector<std::uint8_t>> base64_decode(std::string_view text);

}  // namespace uavsim::common
