#include "objects/eight_track.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "uavsim/common/angles.hpp"

namespace uavsim::server::objects {
namespace {

constexpr double kTol = 1e-9;
constexpr double kQuotedTol_m = 0.01;  // lengths quoted to the centimetre
constexpr double kShortStepTol_m = 1e-6;

TEST(EightTrack, DefaultLengthMatchesClosedForm) {
  // c = 22.5, phi = asin(20 / 22.5) = 1.09491; a = c cos(phi) = 10.3078
  // L = 4a + 2R(pi + 2 phi) = 41.231 + 40 (3.14159 + 2.18982) = 254.49 m
  const EightTrack t;
  const double phi = std::asin(20.0 / 22.5);
  EXPECT_NEAR(t.length_m(), 4 * 22.5 * std::cos(phi) + 40.0 * (common::kPi + 2 * phi), kTol);
  EXPECT_NEAR(t.length_m(), 254.49, kQuotedTol_m);
}

TEST(EightTrack, IsArcLengthParametrisedAndContinuous) {
  const EightTrack t;
  const double ds = 0.01;
  for (double s = 0.0; s < t.length_m() + 1.0; s += ds) {
    const TrackPoint a = t.at(s), b = t.at(s + ds);
    // a chord of 1 cm on a 20 m circle is shorter than the arc by ds^3 / (24 R^2): negligible
    EXPECT_NEAR((b.position_enu_m - a.position_enu_m).norm(), ds, kShortStepTol_m) << "s = " << s;
    EXPECT_NEAR(a.tangent_enu.norm(), 1.0, kTol);
    // the tangent is the derivative of the position
    EXPECT_LT((((b.position_enu_m - a.position_enu_m) / ds) - a.tangent_enu).norm(), 1e-3) << s;
  }
}

TEST(EightTrack, CrossesItselfAtTheCentreHalfwayRound) {
  EightTrackParams p;
  p.centre_enu_m = Eigen::Vector2d(3, -2);
  p.yaw_rad = 0.3;
  const EightTrack t(p);
  EXPECT_LT((t.at(0.0).position_enu_m - p.centre_enu_m).norm(), 1e-9);
  EXPECT_LT((t.at(0.5 * t.length_m()).position_enu_m - p.centre_enu_m).norm(), 1e-9);
  // the two passes cross at angle 2 phi, not along the same line
  EXPECT_GT(std::abs(t.at(0.0).tangent_enu.dot(t.at(0.5 * t.length_m()).tangent_enu)), 0.0);
  EXPECT_LT(t.at(0.0).tangent_enu.dot(t.at(0.5 * t.length_m()).tangent_enu), 0.99);
}

TEST(EightTrack, DefaultEightFillsTheArenaWithin90By60) {
  const EightTrack t;
  Eigen::Vector2d lo(1e9, 1e9), hi(-1e9, -1e9);
  for (double s = 0.0; s < t.length_m(); s += 0.05) {
    lo = lo.cwiseMin(t.at(s).position_enu_m);
    hi = hi.cwiseMax(t.at(s).position_enu_m);
  }
  // x: +-(c + R) = +-42.5 m; y: +-R = +-20 m
  EXPECT_NEAR(hi.x() - lo.x(), 85.0, kQuotedTol_m);
  EXPECT_NEAR(hi.y() - lo.y(), 40.0, kQuotedTol_m);
  EXPECT_LE(hi.x(), 45.0);
  EXPECT_GE(lo.x(), -45.0);
  EXPECT_LE(hi.y(), 30.0);
  EXPECT_GE(lo.y(), -30.0);
}

TEST(EightTrack, CurvatureIsPlusMinusOneOverRadiusOnTheCircles) {
  const EightTrack t;
  const double a = 22.5 * std::cos(std::asin(20.0 / 22.5));
  EXPECT_DOUBLE_EQ(t.at(0.5 * a).curvature_1_m, 0.0);
  EXPECT_DOUBLE_EQ(t.at(a + 1.0).curvature_1_m, -1.0 / 20.0);  // right circle, clockwise
  EXPECT_DOUBLE_EQ(t.at(t.length_m() - a - 1.0).curvature_1_m, 1.0 / 20.0);  // left, counter-clockwise
}

TEST(EightTrack, DistanceIsZeroOnTheTrackAndGrowsOffIt) {
  EightTrackParams p;
  p.yaw_rad = -0.7;
  p.centre_enu_m = Eigen::Vector2d(10, 5);
  const EightTrack t(p);
  for (double s = 0.0; s < t.length_m(); s += 0.37) {
    // near the crossing the offset point is nearer the other straight
    if (std::min({s, std::abs(s - 0.5 * t.length_m()), t.length_m() - s}) < 2.0) continue;
    const TrackPoint tp = t.at(s);
    EXPECT_LT(t.distance_m(tp.position_enu_m), 1e-9) << s;
    const Eigen::Vector2d left(-tp.tangent_enu.y(), tp.tangent_enu.x());
    EXPECT_NEAR(t.distance_m(tp.position_enu_m + 0.5 * left), 0.5, kShortStepTol_m) << s;
  }
}

TEST(EightTrack, RejectsCirclesThatOverlap) {
  EightTrackParams p;
  p.circle_radius_m = 25.0;
  p.centre_separation_m = 45.0;
  EXPECT_FALSE(validate(p).empty());
  EXPECT_TRUE(validate(EightTrackParams{}).empty());
}

TEST(SpeedProfile, FifteenKmhForEightMinutesThenFive) {
  const SpeedProfile s;
  EXPECT_DOUBLE_EQ(s.speed_m_s(0.0), 15.0 / 3.6);
  EXPECT_DOUBLE_EQ(s.speed_m_s(479.9), 15.0 / 3.6);
  EXPECT_DOUBLE_EQ(s.speed_m_s(480.1), 5.0 / 3.6);
  // 8 min at 15 km/h = 2000 m, then 60 s at 5 km/h = 83.33 m
  EXPECT_NEAR(s.arc_length_m(480.0), 2000.0, kTol);
  EXPECT_NEAR(s.arc_length_m(540.0), 2000.0 + 250.0 / 3.0, kTol);
}

}  // namespace
}  // namespace uavsim::server::objects
