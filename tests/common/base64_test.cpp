#include "uavsim/common/base64.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

namespace uavsim::common {
namespace {

using Bytes = std::vector<std::uint8_t>;

TEST(Base64, RoundTripsEveryLength) {
  for (std::size_t n = 0; n < 130; ++n) {
    Bytes b(n);
    for (std::size_t k = 0; k < n; ++k) b[k] = static_cast<std::uint8_t>(k * 37 + n);
    const std::string text = base64_encode(b);
    EXPECT_EQ(text.size(), (n + 2) / 3 * 4) << n;  // always padded
    const auto back = base64_decode(text);
    ASSERT_TRUE(back) << n;
    EXPECT_EQ(*back, b);
  }
}

TEST(Base64, MatchesTheRfcVectors) {
  // RFC 4648 section 10
  const char* plain[] = {"", "f", "fo", "foo", "foob", "fooba", "foobar"};
  const char* coded[] = {"", "Zg==", "Zm8=", "Zm9v", "Zm9vYg==", "Zm9vYmE=", "Zm9vYmFy"};
  for (int k = 0; k < 7; ++k) {
    const std::string p = plain[k];
    EXPECT_EQ(base64_encode(Bytes(p.begin(), p.end())), coded[k]);
    EXPECT_EQ(*base64_decode(coded[k]), Bytes(p.begin(), p.end()));
  }
  EXPECT_EQ(base64_encode(Bytes{0xFF, 0xFE, 0xFD}), "//79");  // the two last alphabet characters
}

TEST(Base64, AcceptsMissingPaddingRejectsGarbage) {
  EXPECT_EQ(*base64_decode("aGk"), (Bytes{'h', 'i'}));  // padding optional
  EXPECT_EQ(*base64_decode("aGk="), (Bytes{'h', 'i'}));
  EXPECT_FALSE(base64_decode("a"));      // 6 bits cannot end a byte
  EXPECT_FALSE(base64_decode("aGk*"));   // outside the alphabet
  EXPECT_FALSE(base64_decode("a=Gk"));   // padding inside
  EXPECT_FALSE(base64_decode("aGk=="));  // padding that does not end a multiple of four
  EXPECT_FALSE(base64_decode("Zg==="));  // three padding characters
  EXPECT_FALSE(base64_decode("aGl="));   // non-zero unused bits: not canonical
  EXPECT_FALSE(base64_decode("aGk\n"));  // no whitespace
}

}  // namespace
}  // namespace uavsim::common
