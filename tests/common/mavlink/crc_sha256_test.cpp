#include <gtest/gtest.h>

#include <string>
#include <string_view>

#include "uavsim/common/mavlink/crc.hpp"
#include "uavsim/common/mavlink/sha256.hpp"
#include "test_util.hpp"

namespace uavsim::common::mavlink {
namespace {

std::span<const std::uint8_t> bytes_of(std::string_view s) {
  return {reinterpret_cast<const std::uint8_t*>(s.data()), s.size()};
}

TEST(Crc, TableMatchesBitwiseReferenceForEveryByteAndState) {
  for (unsigned crc = 0; crc < 0x10000; crc += 257) {
    for (unsigned b = 0; b < 256; ++b) {
      ASSERT_EQ(
          crc_accumulate(static_cast<std::uint8_t>(b), static_cast<std::uint16_t>(crc)),
          crc_accumulate_bitwise(static_cast<std::uint8_t>(b), static_cast<std::uint16_t>(crc)));
    }
  }
}

TEST(Crc, MatchesMcrf4xxCheckValue) {
  // CRC-16/MCRF4XX catalogue check value: crc("123456789") = 0x6F91
  EXPECT_EQ(crc_accumulate(bytes_of("123456789"), kCrcInit), 0x6F91);
}

// FIPS 180-2 appendix B and NIST example vectors
TEST(Sha256, MatchesNistVectors) {
  EXPECT_EQ(test::to_hex(sha256(bytes_of(""))),
            "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
  EXPECT_EQ(test::to_hex(sha256(bytes_of("abc"))),
            "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  EXPECT_EQ(
      test::to_hex(sha256(bytes_of("abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq"))),
      "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1");
  EXPECT_EQ(test::to_hex(
                sha256(bytes_of("abcdefghbcdefghicdefghijdefghijkefghijklfghijklmghijklmnhijklmno"
                                "ijklmnopjklmnopqklmnopqrlmnopqrsmnopqrstnopqrstu"))),
            "cf5b16a778af8380036ce59e7b0492370b249b11e8f07a51afac45037afee9d1");
}

TEST(Sha256, MillionAsInOddChunksMatchesNistVector) {
  const std::string chunk(997, 'a');
  Sha256 h;
  std::size_t left = 1000000;
  while (left > 0) {
    const std::size_t n = std::min(left, chunk.size());
    h.update(bytes_of(std::string_view(chunk).substr(0, n)));
    left -= n;
  }
  EXPECT_EQ(test::to_hex(h.finish()),
            "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0");
}

TEST(Sha256, PaddingBoundariesAgreeBetweenOneShotAndBytewise) {
  // lengths around the 55/56/64-byte padding edges
  for (std::size_t len : {55u, 56u, 57u, 63u, 64u, 65u, 119u, 120u, 128u}) {
    const std::string msg(len, 'x');
    Sha256 h;
    for (char c : msg) h.update(bytes_of(std::string_view(&c, 1)));
    EXPECT_EQ(h.finish(), sha256(bytes_of(msg))) << len;
  }
}

}  // namespace
}  // namespace uavsim::common::mavlink
