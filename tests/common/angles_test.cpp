// wrap_pi: O(1) and total (the loop it replaced spun forever on 1e30).
#include "uavsim/common/angles.hpp"

#include <gtest/gtest.h>

#include <limits>

namespace uavsim::common {
namespace {

constexpr double kUlpTol = 1e-15;  // a few ulps of 1.0

TEST(WrapPi, SmallExcursionsWrapIntoTheHalfOpenInterval) {
  EXPECT_DOUBLE_EQ(wrap_pi(0.5), 0.5);
  EXPECT_DOUBLE_EQ(wrap_pi(kPi + 0.5), -kPi + 0.5);
  EXPECT_DOUBLE_EQ(wrap_pi(-kPi - 0.5), kPi - 0.5);
  EXPECT_DOUBLE_EQ(wrap_pi(7.0 * kPi / 2.0), -kPi / 2.0);
  // (-pi, pi]: pi stays, -pi becomes pi
  EXPECT_DOUBLE_EQ(wrap_pi(kPi), kPi);
  EXPECT_DOUBLE_EQ(wrap_pi(-kPi), kPi);
}

TEST(WrapPi, HugeFiniteAnglesReturnAValueInRange) {
  for (double a : {1e30, -1e30, 3.4e38, 1e300, -std::numeric_limits<double>::max()}) {
    const double w = wrap_pi(a);
    EXPECT_GT(w, -kPi) << a;
    EXPECT_LE(w, kPi) << a;
  }
}

TEST(WrapPi, NonFiniteAnglesGiveZero) {
  EXPECT_EQ(wrap_pi(std::numeric_limits<double>::quiet_NaN()), 0.0);
  EXPECT_EQ(wrap_pi(std::numeric_limits<double>::infinity()), 0.0);
  EXPECT_EQ(wrap_pi(-std::numeric_limits<double>::infinity()), 0.0);
}

TEST(Angles, DegreesAndRadiansConvertBothWays) {
  // 180 deg = pi rad; the two constants are each other's inverse
  EXPECT_DOUBLE_EQ(180.0 * kDegToRad, kPi);
  EXPECT_DOUBLE_EQ(kPi * kRadToDeg, 180.0);
  EXPECT_NEAR(kDegToRad * kRadToDeg, 1.0, kUlpTol);
}

}  // namespace
}  // namespace uavsim::common
