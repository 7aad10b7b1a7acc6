#include "uavsim/vision/eight_track.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace uavsim::vision {
namespace {

constexpr double kTolM = 1e-6;
constexpr double kExactTol = 1e-12;
// lengths quoted to the centimetre, or extremes sampled every 0.1 m
constexpr double kQuotedTolM = 0.01;
// central differences over 1e-4 m
constexpr double kFiniteDiffTol = 1e-5;
constexpr double kFiniteDiffCurvatureTol_1_m = 1e-4;
// a point 5 cm off the crossing projects onto the hinted branch
constexpr double kBranchTolM = 0.2;

TEST(EightTrack, DefaultLengthAndArenaFit) {
  const EightTrack track;
  // c = 22.5, phi = asin(20 / 22.5) = 1.09491 rad, a = c cos(phi) = 10.308 m
  // L = 4a + 2R(pi + 2 phi) = 41.231 + 2 * 20 * 5.33140 = 254.49 m
  EXPECT_NEAR(track.length_m(), 254.49, kQuotedTolM);
  // the eight spans x in [-42.5, 42.5], y in [-20, 20]: inside the 90 x 60 m arena
  double max_x = 0, max_y = 0;
  for (double s = 0; s < track.length_m(); s += 0.1) {
    const Eigen::Vector2d p = track.point_enu(s);
    max_x = std::max(max_x, std::abs(p.x()));
    max_y = std::max(max_y, std::abs(p.y()));
  }
  EXPECT_NEAR(max_x, 42.5, kQuotedTolM);
  EXPECT_NEAR(max_y, 20.0, kQuotedTolM);
  EXPECT_NEAR(track.point_enu(0.0).norm(), 0.0, kTolM);  // s = 0 is the crossing
}

TEST(EightTrack, ArcLengthParametrisationIsUnitSpeedAndSmooth) {
  const EightTrack track({18.0, 44.0, {3.0, -2.0}, 0.4});
  constexpr double kDs = 1e-4;
  for (double s = 0.0; s < track.length_m(); s += 0.37) {
    const Eigen::Vector2d d = (track.point_enu(s + kDs) - track.point_enu(s - kDs)) / (2 * kDs);
    // |dp/ds| = 1 and dp/ds = tangent (also across the joints: tangent continuity)
    EXPECT_NEAR(d.norm(), 1.0, kFiniteDiffTol) << "s=" << s;
    EXPECT_NEAR((d - track.tangent_enu(s)).norm(), 0.0, kFiniteDiffTol) << "s=" << s;
  }
  // closed: the end meets the start
  EXPECT_NEAR((track.point_enu(track.length_m() - 1e-9) - track.point_enu(0.0)).norm(), 0, kTolM);
}

TEST(EightTrack, CurvatureMatchesTurning) {
  const EightTrack track;
  // right circle is run clockwise (turning right: negative), left counter-clockwise
  const double s_right = 10.308 + 50.0;
  const double s_left = 3 * 10.308 + 106.63 + 50.0;
  EXPECT_NEAR(track.curvature_1_m(s_right), -1.0 / 20.0, kExactTol);
  EXPECT_NEAR(track.curvature_1_m(s_left), 1.0 / 20.0, kExactTol);
  EXPECT_EQ(track.curvature_1_m(2.0), 0.0);
  const double ds = 1e-4;
  const Eigen::Vector2d t0 = track.tangent_enu(s_left), t1 = track.tangent_enu(s_left + ds);
  EXPECT_NEAR((t0.x() * t1.y() - t0.y() * t1.x()) / ds, 1.0 / 20.0, kFiniteDiffCurvatureTol_1_m);
}

TEST(EightTrack, ProjectionRecoversArcLengthAndOffset) {
  const EightTrack track({20.0, 45.0, {5.0, 1.0}, -0.3});
  std::mt19937_64 rng(42);
  std::uniform_real_distribution<double> s_dist(0.0, track.length_m());
  std::uniform_real_distribution<double> l_dist(-3.0, 3.0);
  for (int i = 0; i < 500; ++i) {
    const TrackCoordinates truth{s_dist(rng), l_dist(rng)};
    const Eigen::Vector2d p = track.point_enu(truth);
    // the hint picks the branch near the crossing, where the two straights are close
    const TrackCoordinates c = track.project(p, truth.s_m + 2.0);
    EXPECT_NEAR(track.delta_s(truth.s_m, c.s_m), 0.0, kTolM) << "s=" << truth.s_m;
    EXPECT_NEAR(c.l_m, truth.l_m, kTolM) << "s=" << truth.s_m;
  }
}

TEST(EightTrack, HintChoosesBranchAtCrossing) {
  const EightTrack track;
  // at the crossing both branches pass through the origin: s = 0 and s = a + arc + a
  const double a = 10.308, arc = (track.length_m() - 4 * a) / 2;
  const double s_second = 2 * a + arc;
  const Eigen::Vector2d p(0.05, 0.0);
  EXPECT_LT(std::abs(track.delta_s(0.0, track.project(p, 1.0).s_m)), kBranchTolM);
  EXPECT_LT(std::abs(track.delta_s(s_second, track.project(p, s_second - 1.0).s_m)), kBranchTolM);
}

TEST(EightTrack, RejectsOverlappingCircles) {
  EXPECT_THROW(EightTrack({20.0, 39.0, {0, 0}, 0}), std::invalid_argument);
}

}  // namespace
}  // namespace uavsim::vision
