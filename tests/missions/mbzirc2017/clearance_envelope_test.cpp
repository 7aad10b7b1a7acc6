// The clearance envelope around the funnel (clearance_envelope.hpp) against geometry computed by
// hand from the mission config's defaults (models/objects/truck.xml, models/vehicles/hexa.xml):
//   floor      = cab top 0.55 + margin 0.25                          = 0.8 m above the deck
//   box front  = min(deck 1.1 - skids 0.3, cab 2.0 - rotors 0.64) - 0.1 = 0.7 m
//   box rear   = -(1.1 - 0.3 - 0.1)                                  = -0.7 m, half width 0.7 m
//   cab volume = x in [2.0 - 0.74, 3.0 + 0.74] = [1.26, 3.74], |y| <= 1.0 + 0.74 = 1.74,
//                skids in (-0.15 - 0.44, 0.55 + 0.25) = (-0.59, 0.8)
#include "clearance_envelope.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "uavsim/common/angles.hpp"

namespace uavsim::missions::mbzirc2017 {
namespace {

constexpr double kTol = 1e-12;
constexpr double kRotatedTol_m = 1e-9;  // through the truck's rotation

TEST(ClearanceEnvelope, GeometryFromTheMeasuredTruck) {
  const ClearanceEnvelope e{MissionConfig{}};
  EXPECT_NEAR(e.floor_height_m(), 0.8, kTol);
  EXPECT_NEAR(e.box_front_m(), 0.7, kTol);
  EXPECT_NEAR(e.box_rear_m(), -0.7, kTol);
  EXPECT_NEAR(e.box_half_width_m(), 0.7, kTol);
  EXPECT_TRUE(e.in_box({0.7, -0.7}));
  EXPECT_FALSE(e.in_box({0.71, 0.0}));
  EXPECT_FALSE(e.in_box({0.0, 0.71}));
  // the cab's volume, at its edges
  EXPECT_TRUE(e.in_cab_volume({2.5, 0.0, 0.5}));
  EXPECT_FALSE(e.in_cab_volume({1.25, 0.0, 0.5}));  // 1 cm behind the widened rear face
  EXPECT_TRUE(e.in_cab_volume({1.27, 0.0, 0.5}));
  EXPECT_FALSE(e.in_cab_volume({2.5, 0.0, 0.81}));  // above the floor
  EXPECT_FALSE(e.in_cab_volume({2.5, 1.75, 0.5}));  // beside it
  EXPECT_FALSE(e.in_cab_volume({3.75, 0.0, 0.5}));  // ahead of it
}

// A truck heading north (90 deg) turning left at 0.2 rad/s; the UAV 1 m ahead of the marker (in
// ENU: 1 m north) and 1 m above the deck, moving with the truck's point under it.
TEST(ClearanceEnvelope, TruckFrameFollowsTheHeadingAndTheTurn) {
  const MissionConfig c;
  EstimatedTruck t;
  t.marker_enu_m = Eigen::Vector2d(10.0, 5.0);
  t.velocity_enu_m_s = Eigen::Vector2d(0.0, 4.0);
  t.heading_enu_rad = 0.5 * common::kPi;
  t.yaw_rate_rad_s = 0.2;
  // body origin: deck 1.5 + skids 0.362 + 1.0
  const Eigen::Vector3d p(10.0, 6.0, 1.5 + 0.362 + 1.0);
  // the point 1 m ahead moves at v + omega x r = (0, 4) + 0.2 * (-1, 0) = (-0.2, 4)
  const Eigen::Vector3d v(-0.2, 4.0, -0.3);
  const TruckRelative r = to_truck_frame(t, c, p, v);
  EXPECT_NEAR(r.position_m.x(), 1.0, kTol);
  EXPECT_NEAR(r.position_m.y(), 0.0, kTol);
  EXPECT_NEAR(r.position_m.z(), 1.0, kRotatedTol_m);
  EXPECT_NEAR(r.velocity_m_s.head<2>().norm(), 0.0, kTol);
  EXPECT_NEAR(r.velocity_m_s.z(), -0.3, kTol);
  // 1 m/s backwards relative to the truck (truck frame -x = ENU south) on top of the point's
  // velocity
  const Eigen::Vector3d cmd = enu_velocity_for(t, p, Eigen::Vector3d(-1.0, 0.0, 1.5));
  EXPECT_NEAR(cmd.x(), -0.2, kTol);
  EXPECT_NEAR(cmd.y(), 3.0, kTol);
  EXPECT_NEAR(cmd.z(), 1.5, kTol);
  // and back
  EXPECT_NEAR((to_truck_frame(t, c, p, cmd).velocity_m_s - Eigen::Vector3d(-1.0, 0.0, 1.5)).norm(),
              0.0, kTol);
}

TruckRelative at(double x, double y, double z, double vx = 0.0, double vy = 0.0) {
  TruckRelative r;
  r.position_m = Eigen::Vector3d(x, y, z);
  r.velocity_m_s = Eigen::Vector3d(vx, vy, 0.0);
  return r;
}

TEST(ClearanceEnvelope, BelowTheCabOnlyInTheDeckBoxAndMatched) {
  const ClearanceEnvelope e{MissionConfig{}};
  // above the floor anything goes (the funnel decides)
  EXPECT_TRUE(e.check(at(2.5, 0.0, 0.81, 3.0)).safe());
  // 0.6 m forward at 0.5 m above the deck: in the box, matched at 0.1 m/s (0.6 + 0.1 * 0.5 = 0.65)
  EnvelopeCheck c = e.check(at(0.6, 0.0, 0.5, 0.1));
  EXPECT_TRUE(c.in_deck_box);
  EXPECT_TRUE(c.matched);
  EXPECT_TRUE(c.safe());
  EXPECT_FALSE(c.ready_for_open_loop());  // 0.6 m off: not centred (0.45)
  // drifting forward at 0.3 m/s: 0.6 + 0.3 * 0.5 = 0.75 leaves the box within the prediction
  c = e.check(at(0.6, 0.0, 0.5, 0.3));
  EXPECT_FALSE(c.in_deck_box);
  EXPECT_FALSE(c.safe());
  // in the box but 0.6 m/s sideways (0.1 + 0.6 * 0.5 = 0.4, in): not matched (0.5 m/s)
  c = e.check(at(0.0, 0.1, 0.5, 0.0, 0.6));
  EXPECT_TRUE(c.in_deck_box);
  EXPECT_FALSE(c.matched);
  EXPECT_FALSE(c.safe());
  // centred: 0.2 m off at 0.3 m/s; 0.5 m off (in the box, matched) is not
  EXPECT_TRUE(e.check(at(0.2, 0.0, 0.3, -0.3)).ready_for_open_loop());
  c = e.check(at(0.0, 0.5, 0.3));
  EXPECT_TRUE(c.safe());
  EXPECT_FALSE(c.ready_for_open_loop());
}

TEST(ClearanceEnvelope, NoDescentBelowTheFloorUnlessCleared) {
  const ClearanceEnvelope e{MissionConfig{}};
  // out of the box at 1.3 m: the descent at 1 m/s is limited to 1/s * (0.8 - 1.3) = -0.5 m/s
  EXPECT_NEAR(e.limit_vertical_m_s(at(0.9, 0.0, 1.3), -1.0), -0.5, kTol);
  EXPECT_NEAR(e.limit_vertical_m_s(at(0.9, 0.0, 0.8), -1.0), 0.0, kTol);  // holds at the floor
  EXPECT_NEAR(e.limit_vertical_m_s(at(0.9, 0.0, 0.6), -1.0), 0.2, kTol);  // climbs back
  EXPECT_NEAR(e.limit_vertical_m_s(at(0.9, 0.0, 0.6), 0.8), 0.8, kTol);   // a climb stays
  // cleared: unchanged
  EXPECT_NEAR(e.limit_vertical_m_s(at(0.1, 0.0, 0.6), -0.5), -0.5, kTol);
}

TEST(ClearanceEnvelope, AbortRetreatsAlongTheSeparatingFace) {
  const MissionConfig c;
  const ClearanceEnvelope e{c};
  // over the deck, 0.3 m up: rear face (1.26 - 0.5 = 0.76 outside) -> back along the truck and up
  Eigen::Vector3d v = e.abort_velocity_m_s({0.5, 0.2, 0.3});
  EXPECT_NEAR((v - Eigen::Vector3d(-c.abort_retreat_m_s, 0.0, c.abort_climb_m_s)).norm(), 0.0,
              kTol);
  // above the cab (1.5 - 0.8 = 0.7 above the top face, -1.24 behind the rear): straight up
  v = e.abort_velocity_m_s({2.5, 0.0, 1.5});
  EXPECT_NEAR((v - Eigen::Vector3d(0.0, 0.0, c.abort_climb_m_s)).norm(), 0.0, kTol);
  // beside it on the left (2.0 - 1.74 = 0.26 out): out to the left
  v = e.abort_velocity_m_s({2.5, 2.0, 0.2});
  EXPECT_NEAR((v - Eigen::Vector3d(0.0, c.abort_retreat_m_s, c.abort_climb_m_s)).norm(), 0.0, kTol);
  // ahead of it (4.0 - 3.74 = 0.26 out): forward, faster than the truck
  v = e.abort_velocity_m_s({4.0, 0.0, 0.0});
  EXPECT_NEAR((v - Eigen::Vector3d(c.abort_retreat_m_s, 0.0, c.abort_climb_m_s)).norm(), 0.0, kTol);
}

// From every start outside the cab's volume on a 0.1 m grid around the truck (down to 0.5 m
// below the deck: under the cab is its chassis), the climb-away flown in the truck's frame never
// enters the volume.
TEST(ClearanceEnvelope, AbortPathNeverCrossesTheCab) {
  const MissionConfig c;
  const ClearanceEnvelope e{c};
  constexpr double kDt_s = 0.02;
  int starts = 0;
  for (double x = -3.0; x <= 6.0; x += 0.1) {
    for (double y = -3.0; y <= 3.0; y += 0.25) {
      for (double z = -0.5; z <= 2.5; z += 0.1) {
        Eigen::Vector3d p(x, y, z);
        if (e.in_cab_volume(p)) continue;
        ++starts;
        for (int k = 0; k < 100; ++k) {  // 2 s
          p += e.abort_velocity_m_s(p) * kDt_s;
          ASSERT_FALSE(e.in_cab_volume(p)) << "from (" << x << ", " << y << ", " << z << ")";
        }
        ASSERT_GE(p.z(), z + 2.0 * c.abort_climb_m_s - 1e-6);  // and it climbed all the way
      }
    }
  }
  EXPECT_GT(starts, 10000);
}

}  // namespace
}  // namespace uavsim::missions::mbzirc2017
