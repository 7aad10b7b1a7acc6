// The launcher's near-miss scoring (near_miss.hpp) on the project's own models, against geometry
// computed by hand from models/objects/truck.xml and models/vehicles/hexa.xml.
#include "near_miss.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

#include "uavsim/common/angles.hpp"

namespace uavsim::missions::mbzirc2017 {
namespace {

const std::string kModels = UAVSIM_MODELS_DIR;
constexpr double kRimTol_m = 0.19 * (1.0 - 0.99144);  // 24 rim points: r (1 - cos(pi / 24))

// box faces and distances: a few additions and subtractions
constexpr double kExactTol_m = 1e-12;
constexpr double kClearanceTol_m = 1e-9;

TEST(NearMiss, LoadsTheTrucksCollidingBoxes) {
  const TruckShape t = load_truck_shape(kModels + "/objects/truck.xml");
  EXPECT_EQ(t.deck.name, "deck");
  EXPECT_NEAR(t.deck.centre_m.z() + t.deck.half_m.z(), 1.5, kExactTol_m);  // the deck's top
  ASSERT_EQ(t.parts.size(), 2u);  // chassis and cab; the marker and wheels are visual
  EXPECT_EQ(t.parts[0].name, "chassis");
  EXPECT_EQ(t.parts[1].name, "cab");
  EXPECT_NEAR(t.parts[1].centre_m.x() - t.parts[1].half_m.x(), 2.0, kExactTol_m);  // its rear face
}

TEST(NearMiss, LoadsTheHexasCollidingGeoms) {
  const VehicleShape v = load_vehicle_shape(kModels + "/vehicles/hexa.xml");
  // hull and six propellers: 2 rims of 24 + 2 centres each (7 x 50); two skids: 9 points each
  EXPECT_EQ(v.spheres.size(), 7u * 50u + 2u * 9u);
  ASSERT_EQ(v.gear_points_m.size(), 4u);
  for (const Eigen::Vector3d& g : v.gear_points_m) {
    EXPECT_NEAR(std::abs(g.x()), 0.2, kExactTol_m);
    EXPECT_NEAR(g.z(), -0.362, kExactTol_m);  // skid axis 0.35 below, radius 0.012
  }
}

TEST(NearMiss, RejectsWhatItCannotScore) {
  const std::string path = ::testing::TempDir() + "near_miss_rotated.xml";
  std::ofstream(path) << R"(<mujoco><worldbody><body name="t">
      <geom name="deck" type="box" size="1 1 0.05"/>
      <geom name="cab" type="box" size="1 1 1" euler="0 0 0.3"/>
    </body></worldbody></mujoco>)";
  EXPECT_THROW(load_truck_shape(path), std::runtime_error);
  EXPECT_THROW(load_truck_shape(path + ".missing"), std::runtime_error);
}

TEST(NearMiss, BoxDistanceIsSigned) {
  BodyBox cab{"cab", Eigen::Vector3d(2.5, 0, 1.7), Eigen::Vector3d(0.5, 1.0, 0.35)};
  EXPECT_NEAR(box_distance_m(cab, {3.5, 0, 1.7}), 0.5, kExactTol_m);
  EXPECT_NEAR(box_distance_m(cab, {3.3, 1.3, 2.45}), std::sqrt(0.09 + 0.09 + 0.16), kExactTol_m);
  // inside: to the nearest face
  EXPECT_NEAR(box_distance_m(cab, {2.5, 0, 1.7}), -0.35, kExactTol_m);
}

// The hexa sitting centred on the deck of a truck heading north-east: skids 0.9 m from the deck's
// edges; the nearest colliding point to the cab is a propeller tip, 0.3897 + 0.19 = 0.5797 m
// forward at 1.5 + 0.362 + 0.07 = 1.932 m (within the cab's 1.35-2.05 m), 2.0 - 0.5797 m from it.
TEST(NearMiss, CentredOnTheDeck) {
  NearMissTracker t(load_truck_shape(kModels + "/objects/truck.xml"),
                    load_vehicle_shape(kModels + "/vehicles/hexa.xml"));
  const double yaw = common::kPi / 4;
  const Eigen::Vector3d truck(10, 20, 0);
  const Eigen::Quaterniond q(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()));
  t.add(truck + Eigen::Vector3d(0, 0, 1.862), q, truck, yaw);
  ASSERT_TRUE(t.min_clearance_m("cab"));
  EXPECT_NEAR(*t.min_clearance_m("cab"), 2.0 - 0.5797, kClearanceTol_m);
  EXPECT_NEAR(*t.min_clearance_m("chassis"), 0.1, kClearanceTol_m);  // through the deck
  ASSERT_TRUE(t.min_deck_edge_margin_m());
  EXPECT_NEAR(*t.min_deck_edge_margin_m(), 0.9, kClearanceTol_m);
}

// Moving forward from the centre to 1.5 m at propeller height: the tips reach 2.08 m, 8 cm into
// the cab (a contact); the samples in between are interpolated, and the skids (1.5 + 0.2 = 1.7 m)
// hang over the deck's front edge (1.1 m) by 0.6 m.
TEST(NearMiss, PropellerIntoTheCabIsANegativeClearance) {
  NearMissTracker t(load_truck_shape(kModels + "/objects/truck.xml"),
                    load_vehicle_shape(kModels + "/vehicles/hexa.xml"));
  const Eigen::Quaterniond level = Eigen::Quaterniond::Identity();
  t.add(Eigen::Vector3d(0, 0, 1.862), level, Eigen::Vector3d::Zero(), 0.0);
  t.add(Eigen::Vector3d(1.5, 0, 1.862), level, Eigen::Vector3d::Zero(), 0.0);
  EXPECT_NEAR(*t.min_clearance_m("cab"), 2.0 - 2.0797, kRimTol_m);
  EXPECT_NEAR(*t.min_deck_edge_margin_m(), 1.1 - 1.7, kClearanceTol_m);
  // far away (50 m), the bound stays the minimum
  t.add(Eigen::Vector3d(50, 0, 8), level, Eigen::Vector3d::Zero(), 0.0);
  EXPECT_LT(*t.min_clearance_m("cab"), 0.0);
}

// Beside the truck at the deck's height (climbing away past its side) is no landing: no deck-edge
// margin from there.
TEST(NearMiss, BesideTheDeckAtItsHeightIsNoLanding) {
  NearMissTracker t(load_truck_shape(kModels + "/objects/truck.xml"),
                    load_vehicle_shape(kModels + "/vehicles/hexa.xml"));
  t.add(Eigen::Vector3d(2.5, 4.0, 1.862), Eigen::Quaterniond::Identity(), Eigen::Vector3d::Zero(),
        0.0);
  EXPECT_FALSE(t.min_deck_edge_margin_m());
  ASSERT_TRUE(t.min_clearance_m("cab"));
  // beside the cab (x 2.5): propeller 4's tip 4 - 0.45 - 0.19 = 3.36 m out, the cab's side 1.0 m
  EXPECT_NEAR(*t.min_clearance_m("cab"), 3.36 - 1.0, kRimTol_m);
}

TEST(NearMiss, PartsOfTheEight) {
  const vision::EightTrack track;
  // R 20, D 45: half straight a = 22.5 cos(asin(20 / 22.5)) = 10.31 m
  const double a = 22.5 * std::cos(std::asin(20.0 / 22.5));
  EXPECT_EQ(eight_part(track, 0.0), "crossing");
  EXPECT_EQ(eight_part(track, 4.9), "crossing");
  EXPECT_EQ(eight_part(track, track.length_m() - 4.9), "crossing");
  EXPECT_EQ(eight_part(track, 0.5 * track.length_m() + 3.0), "crossing");
  EXPECT_EQ(eight_part(track, 8.0), "straight");
  EXPECT_EQ(eight_part(track, a + 10.0), "curve");
  EXPECT_EQ(eight_part(track, 0.75 * track.length_m()), "curve");
}

}  // namespace
}  // namespace uavsim::missions::mbzirc2017
