// The one pinhole model (common/pinhole.hpp) against hand-computed numbers: the renderer states a frame's
// intrinsics with it and vision projects with it, so a convention error here would move every detection.
#include "uavsim/common/pinhole.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "uavsim/common/angles.hpp"

namespace uavsim::common {
namespace {

constexpr double kExact = 1e-12;  // closed-form arithmetic on a few doubles
constexpr double kRayDirTol = 1e-9;

TEST(Pinhole, NinetyDegreeFovyPutsTheImageEdgeAtOneFocalLength) {
  // fovy 90 deg: tan(45 deg) = 1, so fy = h/2; the axis between the middle pixels of an even image
  const PinholeIntrinsics k = PinholeIntrinsics::from_fovy(640, 480, kPi / 2);
  EXPECT_NEAR(k.fy_px, 240.0, kExact);
  EXPECT_NEAR(k.fx_px, 240.0, kExact);
  EXPECT_DOUBLE_EQ(k.cx_px, 319.5);
  EXPECT_DOUBLE_EQ(k.cy_px, 239.5);
  EXPECT_EQ(k.width_px, 640);
  EXPECT_EQ(k.height_px, 480);
}

TEST(Pinhole, DegreeAndRadianFormsAgree) {
  for (const double fovy_deg : {10.0, 45.0, 60.0, 90.0, 120.0}) {
    const PinholeIntrinsics d = PinholeIntrinsics::from_fovy_deg(384, 216, fovy_deg);
    const PinholeIntrinsics r = PinholeIntrinsics::from_fovy(384, 216, fovy_deg * kPi / 180.0);
    EXPECT_NEAR(d.fy_px, r.fy_px, kExact * r.fy_px) << fovy_deg;
    EXPECT_DOUBLE_EQ(d.cx_px, r.cx_px);
    EXPECT_DOUBLE_EQ(d.cy_px, r.cy_px);
  }
}

TEST(Pinhole, FovyOfAFocalLengthInvertsFromFovy) {
  // fy = h/2 puts the image edge at 45 deg off the axis: fovy = 2 atan(1) = 90 deg
  EXPECT_NEAR(PinholeIntrinsics::fovy_deg_of(480, 240.0), 90.0, kExact);
  for (const double fovy_deg : {10.0, 45.0, 60.0, 90.0, 120.0}) {
    const PinholeIntrinsics k = PinholeIntrinsics::from_fovy_deg(384, 216, fovy_deg);
    EXPECT_NEAR(PinholeIntrinsics::fovy_deg_of(k.height_px, k.fy_px), fovy_deg, kExact * 1e2)
        << fovy_deg;
  }
}

TEST(Pinhole, ProjectAndRayAreInverse) {
  const PinholeIntrinsics k = PinholeIntrinsics::from_fovy_deg(640, 480, 60.0);
  // on the axis: the principal point
  const Eigen::Vector2d c = k.project({0.0, 0.0, 5.0});
  EXPECT_NEAR(c.x(), 319.5, kExact);
  EXPECT_NEAR(c.y(), 239.5, kExact);
  // one metre right and half a metre down at 4 m: u = cx + fx / 4, v = cy + fy / 8
  const Eigen::Vector2d p = k.project({1.0, 0.5, 4.0});
  EXPECT_NEAR(p.x(), 319.5 + k.fx_px / 4.0, kExact * 1e3);
  EXPECT_NEAR(p.y(), 239.5 + k.fy_px / 8.0, kExact * 1e3);
  const Eigen::Vector3d ray = k.ray_cam(p);
  EXPECT_NEAR(ray.norm(), 1.0, kExact);
  EXPECT_NEAR((ray - Eigen::Vector3d(1.0, 0.5, 4.0).normalized()).norm(), 0.0, kRayDirTol);
}

TEST(Pinhole, ContainsReachesHalfAPixelPastTheCentres) {
  const PinholeIntrinsics k = PinholeIntrinsics::from_fovy_deg(4, 2, 45.0);
  EXPECT_TRUE(k.contains({-0.5, -0.5}));
  EXPECT_TRUE(k.contains({3.49, 1.49}));
  EXPECT_FALSE(k.contains({3.5, 0.0}));
  EXPECT_FALSE(k.contains({0.0, 1.5}));
  EXPECT_FALSE(k.contains({-0.51, 0.0}));
}

}  // namespace
}  // namespace uavsim::common
