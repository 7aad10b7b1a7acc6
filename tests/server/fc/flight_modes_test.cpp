// The mode objects alone, over a vehicle context built directly (no control loop): what each mode
// needs and allows, and the state a mode keeps (AUTO's phase, RTL's stage, STABILIZE's held
// collective).
#include "fc/flight_modes.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "fc/fc_impl.hpp"
#include "test_airframes.hpp"

namespace uavsim::server::fc {
namespace {

constexpr double kTol = 1e-12;

TEST(FlightModes, NeedsAndAllowsAsArduCopter) {
  FlightModes modes;
  // ArduCopter's requires_GPS and allows_arming, and the modes that read the pilot's sticks
  struct Row {
    Mode mode;
    bool position, arming, pilot;
  };
  const Row rows[] = {
      {Mode::kStabilize, false, true, true}, {Mode::kAltHold, false, true, true},
      {Mode::kGuided, true, true, false},    {Mode::kLoiter, true, true, true},
      {Mode::kBrake, true, false, false},    {Mode::kLand, false, false, false},
      {Mode::kRtl, true, false, false},      {Mode::kAuto, true, false, false},
  };
  for (const Row& r : rows) {
    const FlightMode& m = modes.of(r.mode);
    EXPECT_EQ(m.id(), r.mode);
    EXPECT_EQ(m.needs_position(), r.position) << mode_name(r.mode);
    EXPECT_EQ(m.allows_arming(), r.arming) << mode_name(r.mode);
    EXPECT_EQ(m.reads_pilot(), r.pilot) << mode_name(r.mode);
  }
  // LAND and RTL disarm on the ground at once and end the flight at touchdown; LAND is always
  // landing
  EXPECT_TRUE(modes.land.disarms_when_landed() && modes.land.landing() &&
              modes.land.ends_flight_at_touchdown());
  EXPECT_TRUE(modes.rtl.disarms_when_landed() && modes.rtl.ends_flight_at_touchdown());
  EXPECT_FALSE(modes.automatic.disarms_when_landed());
}

// a vehicle context as the controller builds it, on the ground at the origin, armed
struct Context {
  Context() : v(test::make_quad(), 7) { v.armed_ = true; }
  FlightController::Impl v;
};

TEST(FlightModes, StabilizeHoldsTheCollectiveItWasEnteredWith) {
  Context c;
  c.v.mixer_status_.thrust_n = 14.7;  // hover of a 1.5 kg quad: 1.5 * 9.81
  c.v.modes_.stabilize.enter(c.v, true);
  EXPECT_EQ(c.v.fixed_thrust_n_, 14.7);
  c.v.modes_.stabilize.enter(c.v, false);  // on the ground: idle
  EXPECT_EQ(c.v.fixed_thrust_n_, 0.0);
}

TEST(FlightModes, AutoPhasesFollowTheItems) {
  Context c;
  MissionItem land_here;  // LAND without a position: descend where it is
  land_here.kind = MissionItem::Kind::kLand;
  land_here.position_valid = false;
  MissionItem rtl;
  rtl.kind = MissionItem::Kind::kRtl;
  MissionItem yaw;
  yaw.kind = MissionItem::Kind::kConditionYaw;
  yaw.yaw_enu_rad = 3.0 * M_PI / 2.0;  // 270 deg ENU = -90 deg once wrapped
  c.v.mission_ = {MissionItem{}, land_here, rtl, yaw};
  AutoMode& a = c.v.modes_.automatic;

  a.start_item(c.v, 1);
  EXPECT_TRUE(a.landing());
  EXPECT_TRUE(a.ends_flight_at_touchdown());
  // RTL item: the RTL object climbs first (not landing yet), but a touchdown would end the flight
  a.start_item(c.v, 2);
  EXPECT_FALSE(a.landing());
  EXPECT_TRUE(a.ends_flight_at_touchdown());
  EXPECT_FALSE(c.v.modes_.rtl.landing());
  // CONDITION_YAW: the heading target, wrapped to (-pi, pi]
  a.start_item(c.v, 3);
  EXPECT_NEAR(c.v.yaw_target_rad_, -M_PI / 2.0, kTol);
  EXPECT_TRUE(c.v.yaw_fixed_);
  EXPECT_FALSE(a.ends_flight_at_touchdown());
  // past the end: mission complete, holding at the last item
  a.complete_item(c.v);
  EXPECT_EQ(c.v.mission_current_, 3);
  EXPECT_FALSE(a.landing());
  std::vector<int> reached;
  c.v.reached_.drain([&](int seq) { reached.push_back(seq); });
  EXPECT_EQ(reached, std::vector<int>{3});
}

TEST(FlightModes, LandDescendsWhereTheHoldWas) {
  Context c;
  c.v.hold_position_enu_m_ = Eigen::Vector3d(3.0, -4.0, 10.0);
  c.v.modes_.land.enter(c.v, true);
  EXPECT_EQ(c.v.land_xy_enu_m_, Eigen::Vector3d(3.0, -4.0, 10.0));
}

}  // namespace
}  // namespace uavsim::server::fc
