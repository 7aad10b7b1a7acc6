// sim::checked_integer / finite_in: the one gate for numbers from outside before a cast.
#include "sim/checked_number.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <limits>

namespace uavsim::server::sim {
namespace {

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

TEST(CheckedInteger, AcceptsWholeNumbersInRange) {
  EXPECT_EQ(checked_integer<std::uint32_t>(4.0), 4u);
  EXPECT_EQ(checked_integer<std::uint32_t>(4294967295.0), 4294967295u);
  EXPECT_EQ(checked_integer<std::int32_t>(-2147483648.0), INT32_MIN);
  EXPECT_EQ(checked_integer<std::uint8_t>(255.0), 255);
  EXPECT_EQ(checked_integer<std::uint64_t>(9007199254740992.0), 9007199254740992ull);
}

TEST(CheckedInteger, RefusesWhatTheTargetCannotHold) {
  EXPECT_FALSE(checked_integer<std::uint32_t>(4294967296.0));
  EXPECT_FALSE(checked_integer<std::uint32_t>(1e30));
  EXPECT_FALSE(checked_integer<std::uint32_t>(-1.0));
  EXPECT_FALSE(checked_integer<std::int32_t>(2147483648.0));
  EXPECT_FALSE(checked_integer<std::uint8_t>(256.0));
  // 2^64 is what (double)UINT64_MAX rounds to: still out of range
  EXPECT_FALSE(checked_integer<std::uint64_t>(18446744073709551616.0));
  EXPECT_FALSE(checked_integer<std::int64_t>(9223372036854775808.0));
  EXPECT_FALSE(checked_integer<int>(kNan));
  EXPECT_FALSE(checked_integer<int>(kInf));
  EXPECT_FALSE(checked_integer<int>(2.5));
}

TEST(CheckedInteger, HonoursAnExtraRange) {
  EXPECT_EQ(checked_integer<int>(3.0, 0, 3), 3);
  EXPECT_FALSE(checked_integer<int>(4.0, 0, 3));
  EXPECT_FALSE(checked_integer<int>(-1.0, 0, 3));
}

TEST(FiniteIn, ChecksBoundsAndFiniteness) {
  EXPECT_TRUE(finite_in(1.0, 0.0, 1.0));
  EXPECT_FALSE(finite_in(1.5, 0.0, 1.0));
  EXPECT_FALSE(finite_in(kNan, 0.0, 1.0));
  EXPECT_FALSE(finite_in(kInf, 0.0, kInf));
}

}  // namespace
}  // namespace uavsim::server::sim
