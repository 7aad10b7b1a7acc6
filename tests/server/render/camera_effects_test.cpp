// Field camera effects (render/frame_service.hpp, apply_sensor_effects): pixel noise and brightness
// variation with their configured statistics, drawn from (seed, camera, frame index).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "render/frame_service.hpp"

namespace uavsim::server::render {
namespace {

TEST(CameraEffects, PixelNoiseHasTheConfiguredDeviation) {
  // 640 x 480 x 3 mid-grey values: the sample sd is exact to ~0.1 %; the four-uniform sum is
  // Gaussian-like (unit variance by construction): allow 3 %
  std::vector<uint8_t> px(640 * 480 * 3, 128);
  apply_sensor_effects(10.0, 0.0, 1, 0, 0, &px);
  double sum = 0.0, sum2 = 0.0;
  for (uint8_t p : px) {
    sum += p;
    sum2 += static_cast<double>(p) * p;
  }
  const double n = static_cast<double>(px.size());
  const double mean = sum / n;
  EXPECT_NEAR(mean, 128.0, 0.1);
  EXPECT_NEAR(std::sqrt(sum2 / n - mean * mean), 10.0, 0.3);
}

TEST(CameraEffects, BrightnessVariesPerFrameWithTheConfiguredDeviation) {
  // one grey pixel per frame, no noise: the value is 100 * gain; 4000 frames: sd within ~1 %
  double sum = 0.0, sum2 = 0.0;
  constexpr int kFrames = 4000;
  for (int k = 0; k < kFrames; ++k) {
    std::vector<uint8_t> px(3, 100);
    apply_sensor_effects(0.0, 0.08, 7, 1, k, &px);
    EXPECT_EQ(px[0], px[1]);  // one gain for the whole frame
    const double gain = px[0] / 100.0;
    sum += gain;
    sum2 += gain * gain;
  }
  const double mean = sum / kFrames;
  EXPECT_NEAR(mean, 1.0, 0.01);
  EXPECT_NEAR(std::sqrt(sum2 / kFrames - mean * mean), 0.08,
              0.004 + 0.01 * 0.5);  // + rounding to 1/100
}

TEST(CameraEffects, PixelRoundingIsLroundClampedToTheBit) {
  const auto reference = [](double v) {
    return static_cast<uint8_t>(std::clamp(std::lround(v), 0L, 255L));
  };
  // every half and its neighbours one ulp away (the ties lround breaks away from zero), and a fine
  // sweep across and beyond [0, 255]
  for (int k = -4; k <= 520; ++k) {
    const double half = 0.5 * k;
    for (double v : {half, std::nextafter(half, -1e9), std::nextafter(half, 1e9)}) {
      EXPECT_EQ(round_to_pixel(v), reference(v)) << v;
    }
  }
  for (double v = -3.0; v < 259.0; v += 0.001) ASSERT_EQ(round_to_pixel(v), reference(v)) << v;
  EXPECT_EQ(round_to_pixel(std::numeric_limits<double>::quiet_NaN()), 0);
  EXPECT_EQ(round_to_pixel(1e300), 255);
  EXPECT_EQ(round_to_pixel(-1e300), 0);
  EXPECT_EQ(round_to_pixel(std::numeric_limits<double>::infinity()), 255);
}

TEST(CameraEffects, SameSeedCameraAndFrameSameImage) {
  std::vector<uint8_t> a(1000, 80), b(1000, 80), c(1000, 80), d(1000, 80);
  apply_sensor_effects(5.0, 0.05, 3, 0, 9, &a);
  apply_sensor_effects(5.0, 0.05, 3, 0, 9, &b);
  apply_sensor_effects(5.0, 0.05, 3, 0, 10, &c);
  apply_sensor_effects(5.0, 0.05, 3, 1, 9, &d);
  EXPECT_EQ(a, b);
  EXPECT_NE(a, c);
  EXPECT_NE(a, d);
}

}  // namespace
}  // namespace uavsim::server::render
