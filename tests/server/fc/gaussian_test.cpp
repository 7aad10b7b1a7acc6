#include "fc/gaussian.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace uavsim::server::fc {
namespace {

constexpr int kSamples = 1000000;

TEST(Gaussian, MomentsAndTailsAreThoseOfAStandardNormal) {
  Gaussian g(42);
  double sum = 0, sum2 = 0, sum4 = 0;
  int beyond_1 = 0, beyond_3 = 0, beyond_4 = 0;
  for (int i = 0; i < kSamples; ++i) {
    const double x = g();
    sum += x;
    sum2 += x * x;
    sum4 += x * x * x * x;
    beyond_1 += std::abs(x) > 1.0;
    beyond_3 += std::abs(x) > 3.0;
    beyond_4 += std::abs(x) > 4.0;  // past the ziggurat's base strip (3.44): the tail algorithm
  }
  const double n = kSamples;
  // the mean of n samples has sd 1/sqrt(n) = 0.001: 5 sd
  EXPECT_NEAR(sum / n, 0.0, 0.005);
  // the variance estimate has sd sqrt(2/n) = 0.0014
  EXPECT_NEAR(sum2 / n, 1.0, 0.007);
  // E[x^4] = 3 with sd sqrt((105 - 9)/n) = 0.0098
  EXPECT_NEAR(sum4 / n, 3.0, 0.05);
  // P(|x| > 1) = 0.3173, P(|x| > 3) = 0.0027, P(|x| > 4) = 6.33e-5: binomial 5 sd
  EXPECT_NEAR(beyond_1 / n, 0.3173, 5 * std::sqrt(0.3173 * 0.6827 / n));
  EXPECT_NEAR(beyond_3 / n, 0.0027, 5 * std::sqrt(0.0027 / n));
  EXPECT_NEAR(beyond_4 / n, 6.33e-5, 5 * std::sqrt(6.33e-5 / n));
}

TEST(Gaussian, TheSameSeedGivesTheSameSequenceAndAnotherSeedAnother) {
  Gaussian a(7), b(7), c(8);
  int same_as_c = 0;
  for (int i = 0; i < 1000; ++i) {
    const double x = a();
    ASSERT_EQ(x, b());
    same_as_c += x == c();
  }
  EXPECT_EQ(same_as_c, 0);
}

TEST(Gaussian, UniformCoversTheUnitInterval) {
  Gaussian g(0);  // seed 0 is a seed like any other
  double lo = 1, hi = 0, sum = 0;
  for (int i = 0; i < kSamples; ++i) {
    const double u = g.uniform();
    ASSERT_GE(u, 0.0);
    ASSERT_LT(u, 1.0);
    lo = std::min(lo, u);
    hi = std::max(hi, u);
    sum += u;
  }
  EXPECT_LT(lo, 1e-4);
  EXPECT_GT(hi, 1 - 1e-4);
  // mean 1/2 with sd sqrt(1/12 n) = 0.00029
  EXPECT_NEAR(sum / kSamples, 0.5, 0.0015);
}

}  // namespace
}  // namespace uavsim::server::fc
