#include <gtest/gtest.h>

#include <cmath>

#include "uavsim/common/frames.hpp"
#include "uavsim/common/geodesy.hpp"

namespace uavsim::common {
namespace {

constexpr double kExactTol = 1e-12;  // closed-form arithmetic on a few doubles
constexpr double kPosTol_m = 1e-9;
// the reference distances are quoted to 8 significant digits
constexpr double kRefTol_m = 1e-6;     // 1.1131885 m
constexpr double kRefTenTol_m = 1e-5;  // 11.131885 m
constexpr double kRoundTripTol_m = 1e-6;
constexpr double kAngleTol_rad = 1e-9;
constexpr double kAngleTol_deg = 1e-9;

TEST(Geodesy, OriginMapsToZero) {
  const GeodeticOrigin o;
  const Eigen::Vector3d p = ned_from_geodetic(o, {o.lat_deg, o.lon_deg, o.alt_m});
  EXPECT_NEAR(p.norm(), 0.0, kPosTol_m);
}

TEST(Geodesy, FollowsSeedEquation61) {
  const GeodeticOrigin o;
  // 1e-5 deg of latitude: R * 1e-5 * pi/180 = 6378100 * 1.7453293e-7 = 1.1131885 m north
  const Eigen::Vector3d n = ned_from_geodetic(o, {o.lat_deg + 1e-5, o.lon_deg, o.alt_m});
  EXPECT_NEAR(n.x(), 1.1131885, kRefTol_m);
  // 1e-5 deg of longitude: 1.1131885 m * cos(47.397742 deg) = 1.1131885 * 0.676906 = 0.7535228 m east
  const Eigen::Vector3d e = ned_from_geodetic(o, {o.lat_deg, o.lon_deg + 1e-5, o.alt_m});
  EXPECT_NEAR(e.y(), 0.7535228, kRefTol_m);
  // 10 m higher is 10 m less down
  EXPECT_NEAR(ned_from_geodetic(o, {o.lat_deg, o.lon_deg, o.alt_m + 10.0}).z(), -10.0, kExactTol);
}

TEST(Geodesy, HeadingRotatesTheLocalFrame) {
  GeodeticOrigin o;
  o.heading_rad = kPi / 2.0;
  // a point north of the origin lies on -y of a frame rotated by 90 deg: Rz * (n, 0) = (0, -n)
  const Eigen::Vector3d p = ned_from_geodetic(o, {o.lat_deg + 1e-4, o.lon_deg, o.alt_m});
  EXPECT_NEAR(p.x(), 0.0, kPosTol_m);
  EXPECT_NEAR(p.y(), -11.131885, kRefTenTol_m);
}

TEST(Geodesy, RoundTripsWithinAMillimetre) {
  GeodeticOrigin o;
  o.heading_rad = 0.3;
  const Eigen::Vector3d p(1234.5, -987.25, -55.5);
  const Eigen::Vector3d back = ned_from_geodetic(o, geodetic_from_ned(o, p));
  EXPECT_NEAR((back - p).norm(), 0.0, kRoundTripTol_m);
}

TEST(Geodesy, EnuIsNedWithTheAxesSwapped) {
  const GeodeticOrigin o;
  // 1e-4 deg north and 10 m up: NED (11.131885, 0, -10) m, ENU (0, 11.131885, 10) m
  const Geodetic p{o.lat_deg + 1e-4, o.lon_deg, o.alt_m + 10.0};
  const Eigen::Vector3d enu = enu_from_geodetic(o, p);
  EXPECT_NEAR(enu.x(), 0.0, kPosTol_m);
  EXPECT_NEAR(enu.y(), 11.131885, kRefTenTol_m);
  EXPECT_NEAR(enu.z(), 10.0, kPosTol_m);
  EXPECT_EQ(enu, frames::enu_from_ned(ned_from_geodetic(o, p)));
  const Geodetic back = geodetic_from_enu(o, enu);
  EXPECT_NEAR(back.lat_deg, p.lat_deg, kExactTol);
  EXPECT_NEAR(back.lon_deg, p.lon_deg, kExactTol);
  EXPECT_NEAR(back.alt_m, p.alt_m, kPosTol_m);
}

TEST(Frames, EnuNedSwapAxesAndFlipUp) {
  const Eigen::Vector3d enu(1.0, 2.0, 3.0);
  EXPECT_EQ(frames::ned_from_enu(enu), Eigen::Vector3d(2.0, 1.0, -3.0));
  EXPECT_EQ(frames::enu_from_ned(frames::ned_from_enu(enu)), enu);
}

TEST(Frames, VehicleFacingEastHasNedYaw90) {
  // identity q_enu_flu: body x along ENU x = east => NED yaw +90 deg, level
  const auto e = frames::euler_from_q_ned_frd(frames::q_ned_frd_from_q_enu_flu(Eigen::Quaterniond::Identity()));
  EXPECT_NEAR(e.yaw_rad, kPi / 2.0, kExactTol);
  EXPECT_NEAR(e.roll_rad, 0.0, kExactTol);
  EXPECT_NEAR(e.pitch_rad, 0.0, kExactTol);
  EXPECT_NEAR(frames::yaw_ned_from_yaw_enu(0.0), kPi / 2.0, kExactTol);
}

TEST(Frames, NoseUpPitchIsPositiveInBothConventions) {
  // FLU: nose up = negative rotation about +y (left); FRD pitch up is positive
  const Eigen::Quaterniond q_enu_flu(Eigen::AngleAxisd(-0.2, Eigen::Vector3d::UnitY()));
  const auto e = frames::euler_from_q_ned_frd(frames::q_ned_frd_from_q_enu_flu(q_enu_flu));
  EXPECT_NEAR(e.pitch_rad, 0.2, kExactTol);
  // and the attitude round-trips
  const Eigen::Quaterniond back = frames::q_enu_flu_from_q_ned_frd(frames::q_ned_frd_from_q_enu_flu(q_enu_flu));
  EXPECT_NEAR(back.angularDistance(q_enu_flu), 0.0, kExactTol);
}

TEST(Frames, BodyYawRotatesForwardIntoHeading) {
  // facing east (NED yaw 90 deg), 1 m forward is 1 m east
  const Eigen::Vector3d v = frames::ned_from_body_yaw({1.0, 0.0, 0.0}, kPi / 2.0);
  EXPECT_NEAR(v.x(), 0.0, kExactTol);
  EXPECT_NEAR(v.y(), 1.0, kExactTol);
}

TEST(Frames, ZyxAnglesRecoverTheRotationsTheyWereBuiltFrom) {
  // q = Rz(yaw) Ry(pitch) Rx(roll) for yaw 2.5, pitch -0.4, roll 0.3 rad: the angles come back
  constexpr double kTol = 1e-12;
  const Eigen::Quaterniond q = Eigen::AngleAxisd(2.5, Eigen::Vector3d::UnitZ()) *
                               Eigen::AngleAxisd(-0.4, Eigen::Vector3d::UnitY()) *
                               Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitX());
  const frames::Euler e = frames::euler_zyx(q);
  EXPECT_NEAR(e.yaw_rad, 2.5, kTol);
  EXPECT_NEAR(e.pitch_rad, -0.4, kTol);
  EXPECT_NEAR(e.roll_rad, 0.3, kTol);
  // pitch saturates at +-90 deg, not NaN, for a quaternion a little off unit length
  const Eigen::Quaterniond up(Eigen::AngleAxisd(kPi / 2.0, Eigen::Vector3d::UnitY()));
  const Eigen::Quaterniond over(up.w() * 1.001, up.x() * 1.001, up.y() * 1.001, up.z() * 1.001);
  EXPECT_NEAR(frames::euler_zyx(over).pitch_rad, kPi / 2.0, kTol);
}

TEST(Frames, EnuAttitudeIsYawFromEastCounterClockwiseAndPitchNoseDown) {
  // the ground-truth records' angles: facing north (ENU yaw +90 deg) with the nose 10 deg up, which
  // in FLU is a negative rotation about the left axis
  constexpr double kTol = 1e-12;
  const Eigen::Quaterniond q_enu_flu =
      Eigen::AngleAxisd(kPi / 2.0, Eigen::Vector3d::UnitZ()) *
      Eigen::AngleAxisd(-10.0 * kDegToRad, Eigen::Vector3d::UnitY());
  const frames::Euler e = frames::euler_from_q_enu_flu(q_enu_flu);
  EXPECT_NEAR(e.yaw_rad * kRadToDeg, 90.0, kAngleTol_deg);
  EXPECT_NEAR(e.pitch_rad, -10.0 * kDegToRad, kTol);
  EXPECT_NEAR(e.roll_rad, 0.0, kTol);
  // the same attitude in MAVLink's terms: yaw 0 (north), pitch +10 deg
  const frames::Euler m = frames::euler_from_q_ned_frd(frames::q_ned_frd_from_q_enu_flu(q_enu_flu));
  EXPECT_NEAR(m.yaw_rad, 0.0, kAngleTol_rad);
  EXPECT_NEAR(m.pitch_rad, 10.0 * kDegToRad, kAngleTol_rad);
}

}  // namespace
}  // namespace uavsim::common
