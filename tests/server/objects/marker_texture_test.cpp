#include "objects/marker_texture.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <iterator>

namespace uavsim::server::objects {
namespace {

TEST(MarkerTexture, CommittedPngIsTheGeneratorsOutput) {
  std::ifstream f(std::string(UAVSIM_MODELS_DIR) + "/objects/truck_marker.png", std::ios::binary);
  ASSERT_TRUE(f) << "models/objects/truck_marker.png missing: build target uavsim_marker_texture";
  const std::vector<uint8_t> committed((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  EXPECT_EQ(committed, encode_png(render_marker(MarkerGeometry{}, 512)))
      << "regenerate with: cmake --build BUILD --target uavsim_marker_texture";
}

TEST(MarkerTexture, RingCrossAndDarkBackgroundAreWhereTheGeometrySays) {
  const MarkerGeometry g;
  const int n = 300;  // 5 mm per pixel
  const RgbImage img = render_marker(g, n);
  auto grey = [&](double x_m, double y_m) {
    const int col = static_cast<int>((x_m + 0.75) / 1.5 * n);
    const int row = static_cast<int>((0.75 - y_m) / 1.5 * n);
    return img.rgb[(static_cast<size_t>(row) * n + col) * 3];
  };
  EXPECT_GT(grey(0.0, 0.0), 200);      // the cross's centre
  EXPECT_GT(grey(0.3, 0.0), 200);      // along an arm
  EXPECT_LT(grey(0.3, 0.3), 50);       // between the arms
  EXPECT_GT(grey(0.0, 0.575), 200);    // the ring, between 0.50 and 0.65 m
  EXPECT_LT(grey(0.0, 0.7), 50);       // outside the ring
  EXPECT_LT(grey(0.72, -0.72), 50);    // a corner
}

}  // namespace
}  // namespace uavsim::server::objects
