// Command-line and environment numbers: only a whole, finite number inside the range is taken.
#include "uavsim/common/parse_number.hpp"

#include <gtest/gtest.h>

#include <cstdint>

namespace uavsim::common {
namespace {

TEST(ParseNumber, DoublesMustBeWholeFiniteAndInRange) {
  double v = -7.0;
  EXPECT_TRUE(parse_double("2.5", 0.0, 10.0, &v));
  EXPECT_EQ(v, 2.5);
  EXPECT_TRUE(parse_double("1e1", 0.0, 10.0, &v));  // the upper edge is inside
  EXPECT_EQ(v, 10.0);
  for (const char* bad :
       {"", " 1", "1 ", "1.5x", "x", "nan", "inf", "-inf", "1e400", "1e-400", "10.001", "-0.1"}) {
    double w = -7.0;
    EXPECT_FALSE(parse_double(bad, 0.0, 10.0, &w)) << '"' << bad << '"';
    EXPECT_EQ(w, -7.0) << "output changed by a refused \"" << bad << '"';
  }
  EXPECT_FALSE(parse_double(nullptr, 0.0, 1.0, &v));
}

TEST(ParseNumber, IntegersAreDigitsOnlyAndNeverWrap) {
  int i = -1;
  EXPECT_TRUE(parse_integer("65535", 1, 65535, &i));
  EXPECT_EQ(i, 65535);
  for (const char* bad : {"65536", "0", "4294967297", "99999999999999999999999", "+5", " 5", "5 ",
                          "5.0", "0x10", ""}) {
    int w = -1;
    EXPECT_FALSE(parse_integer(bad, 1, 65535, &w)) << '"' << bad << '"';
    EXPECT_EQ(w, -1);
  }
  EXPECT_TRUE(parse_integer("-3", -5, 5, &i));
  EXPECT_EQ(i, -3);
  std::uint64_t seed = 0;
  EXPECT_TRUE(parse_integer<std::uint64_t>("18446744073709551615", 0, UINT64_MAX, &seed));
  EXPECT_EQ(seed, UINT64_MAX);
  EXPECT_FALSE(parse_integer<std::uint64_t>("18446744073709551616", 0, UINT64_MAX, &seed));
  EXPECT_FALSE(parse_integer<std::uint64_t>("-1", 0, UINT64_MAX, &seed));  // strtoull would wrap it
}

}  // namespace
}  // namespace uavsim::common
