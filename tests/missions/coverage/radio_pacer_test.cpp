// The agent's pacing of its aggregation frames: a long message goes out over several steps within
// its share of the airtime, so a beacon never waits behind more than a step's worth of fragments.
#include "radio_pacer.hpp"

#include <gtest/gtest.h>

#include <limits>
#include <vector>

namespace uavsim::missions::coverage {
namespace {

constexpr double kAirtimeTol_s = 1e-9;

std::vector<Frame> message(int frames, uint8_t tag) {
  return std::vector<Frame>(static_cast<size_t>(frames), Frame(kMaxFrameBytes, tag));
}

TEST(RadioPacer, AirtimeOfAFullFrameAt250kbits) {
  EXPECT_NEAR(frame_airtime_s(127), 4.256e-3, kAirtimeTol_s);  // (127 + 6) bytes * 8 / 250 kbit/s
  EXPECT_NEAR(frame_airtime_s(0), 0.192e-3, kAirtimeTol_s);
}

TEST(RadioPacer, AShortMessageGoesAtOnceALongOneWithinItsShareStepByStep) {
  RadioPacer pacer(0.75, 0.1);
  EXPECT_TRUE(pacer.idle());
  // after a pause, up to 0.1 s of airtime at once: 23 full frames (97.9 ms)
  pacer.push(message(3, 1));
  EXPECT_EQ(pacer.take(0.05).size(), 3u);
  EXPECT_TRUE(pacer.idle());
  for (int k = 0; k < 4; ++k) EXPECT_TRUE(pacer.take(0.05).empty());  // earning, idle, to 0.1 s
  pacer.push(message(100, 2));
  EXPECT_FALSE(pacer.idle());
  std::vector<size_t> per_step;
  double airtime = 0.0;
  while (!pacer.idle()) {
    const std::vector<Frame> f = pacer.take(0.05);
    for (const Frame& x : f) {
      EXPECT_EQ(x[0], 2);
      airtime += frame_airtime_s(x.size());
    }
    per_step.push_back(f.size());
    ASSERT_LT(per_step.size(), 100u);
  }
  // the burst, then 0.75 x 50 ms = 37.5 ms a step (8 or 9 frames): 100 frames in 10 steps
  ASSERT_EQ(per_step.size(), 10u);
  EXPECT_EQ(per_step[0], 23u);
  for (size_t k = 1; k < per_step.size() - 1; ++k) {
    EXPECT_GE(per_step[k], 8u);
    EXPECT_LE(per_step[k], 9u);
  }
  // never more than the burst and the share earned
  EXPECT_LE(airtime, 0.1 + 0.75 * 0.05 * 10 + 1e-9);
}

TEST(RadioPacer, ASmallShareStillSendsAndBadStepsEarnNothing) {
  RadioPacer pacer(0.01, 0.0);  // 0.5 ms a 50 ms step, and a burst of one full frame
  pacer.push(message(3, 3));
  EXPECT_EQ(pacer.take(0.05).size(), 1u);  // the first from the initial burst
  int steps = 1;
  while (!pacer.idle() && steps < 100) {
    (void)pacer.take(0.05);
    ++steps;
  }
  EXPECT_TRUE(pacer.idle());
  EXPECT_EQ(steps, 19);  // then one every 9 steps (4.256 ms at 0.5 ms a step)
  pacer.push(message(1, 4));
  EXPECT_TRUE(pacer.take(0.0).empty());
  EXPECT_TRUE(pacer.take(-1.0).empty());
  EXPECT_TRUE(pacer.take(std::numeric_limits<double>::quiet_NaN()).empty());
  EXPECT_TRUE(pacer.take(std::numeric_limits<double>::infinity()).empty());
}

}  // namespace
}  // namespace uavsim::missions::coverage
