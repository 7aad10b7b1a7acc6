#include "objects/truck_driver.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "objects/truck.hpp"
#include "objects_fixture.hpp"

namespace uavsim::server::objects {
namespace {

using testing::make_shipped;
using testing::make_world;

constexpr double kLateral_m = 0.5;
constexpr double kWobble = 0.03;
constexpr double kDt_s = 0.01;
// the trapezoid rule against the closed-form offset and arc length
constexpr double kRateTol_m_s = 1e-4;
constexpr double kArcLengthTol_m = 1e-3;
constexpr double kScheduleDistRelTol = 0.03;
constexpr double kRoundOffTol = 1e-12;
constexpr double kDirTol = 1e-9;

DriverParams person() {
  DriverParams p;
  p.lateral_amplitude_m = kLateral_m;
  p.speed_wobble = kWobble;
  return p;
}

TEST(TruckDriver, StaysWithinItsBoundsAndMovesSmoothly) {
  const TruckDriver d(person(), 7, "truck");
  const SpeedProfile schedule;  // 15 km/h, 5 km/h after 480 s
  double max_l = 0.0, max_wobble = 0.0;
  double last_l = d.lateral_m(0.0), last_rate = d.lateral_rate_m_s(0.0);
  for (double t = kDt_s; t < 900.0; t += kDt_s) {
    const double l = d.lateral_m(t);
    max_l = std::max(max_l, std::abs(l));
    max_wobble =
        std::max(max_wobble, std::abs(d.speed_m_s(schedule, t) / schedule.speed_m_s(t) - 1.0));
    // smooth: the offset's rate is its derivative, and the rate changes by at most a bounded
    // acceleration: sum a w^2 <= 0.5 m (2 pi / 10 s)^2 = 0.2 m/s^2
    ASSERT_NEAR((l - last_l) / kDt_s, 0.5 * (d.lateral_rate_m_s(t) + last_rate), kRateTol_m_s) << t;
    ASSERT_LE(std::abs(d.lateral_rate_m_s(t) - last_rate), 0.2 * kDt_s + kRoundOffTol) << t;
    last_l = l;
    last_rate = d.lateral_rate_m_s(t);
  }
  EXPECT_LE(max_l, kLateral_m);
  EXPECT_GT(max_l, 0.2 * kLateral_m);  // it does wander
  EXPECT_LE(max_wobble, kWobble);
  EXPECT_GT(max_wobble, 0.2 * kWobble);
}

TEST(TruckDriver, ArcLengthIsTheIntegralOfTheSpeed) {
  const TruckDriver d(person(), 3, "truck");
  SpeedProfile schedule;
  schedule.switch_time_s = 40.0;
  // trapezoidal integration of the speed across the switch matches the closed form
  double s = d.arc_length_m(schedule, 0.0);
  for (double t = 0.0; t < 80.0 - 1e-9; t += kDt_s) {
    const double a = d.speed_m_s(schedule, t), b = d.speed_m_s(schedule, t + kDt_s);
    s += 0.5 * (a + b) * kDt_s;
    if (std::abs(t + kDt_s - 40.0) < 0.5 * kDt_s)
      s = d.arc_length_m(schedule, t + kDt_s);  // the step
  }
  EXPECT_NEAR(s, d.arc_length_m(schedule, 80.0), kArcLengthTol_m);
  // on average the schedule's distance: 80 s, 40 at 4.17 and 40 at 1.39 m/s = 222 m, +-3 %
  EXPECT_NEAR(d.arc_length_m(schedule, 80.0), 40.0 * (15.0 + 5.0) / 3.6,
              kScheduleDistRelTol * 222.3);
}

TEST(TruckDriver, SameSeedSameDriveOtherSeedAnother) {
  const TruckDriver a(person(), 11, "truck"), b(person(), 11, "truck"), c(person(), 12, "truck");
  const SpeedProfile schedule;
  double diff = 0.0;
  for (double t = 0.0; t < 60.0; t += 0.5) {
    ASSERT_EQ(a.lateral_m(t), b.lateral_m(t));
    ASSERT_EQ(a.arc_length_m(schedule, t), b.arc_length_m(schedule, t));
    diff = std::max(diff, std::abs(a.lateral_m(t) - c.lateral_m(t)));
  }
  EXPECT_GT(diff, 0.05);
}

TEST(TruckDriver, OffMeansTheIdealTrackAtTheScheduledSpeed) {
  const TruckDriver d(DriverParams{}, 5, "truck");
  EXPECT_FALSE(d.enabled());
  const SpeedProfile schedule;
  for (double t = 0.0; t < 600.0; t += 7.3) {
    EXPECT_EQ(d.lateral_m(t), 0.0);
    EXPECT_DOUBLE_EQ(d.arc_length_m(schedule, t), schedule.arc_length_m(t));
    EXPECT_DOUBLE_EQ(d.speed_m_s(schedule, t), schedule.speed_m_s(t));
  }
}

TEST(TruckDriver, BadWorldParametersAreStartupErrors) {
  auto sim = make_world("truck_driver_bad", R"(<uavsim_object type="truck" name="truck"/>)",
                        R"(<numeric name="uavsim:truck:driver" data="3 0.03"/>)");
  EXPECT_THROW(add_world_objects(*sim), physics::WorldError);
  auto sim2 = make_world("truck_driver_bad2", R"(<uavsim_object type="truck" name="truck"/>)",
                         R"(<numeric name="uavsim:truck:driver" data="0.5 -0.1"/>)");
  EXPECT_THROW(add_world_objects(*sim2), physics::WorldError);
}

TEST(TruckDriver, ShippedWorldTruckWandersAroundTheEightAndHeadsWhereItGoes) {
  auto sim = make_shipped("mbzirc2017.xml", 4);
  const ObjectSet set = add_world_objects(*sim);
  const Truck& truck = *set.trucks[0];
  ASSERT_TRUE(truck.driver().enabled());
  double max_off = 0.0;
  for (double t = 0.0; t < 120.0; t += 0.05) {
    const TruckState s = truck.state(t);
    const double off = truck.track().distance_m(s.position_enu_m.head<2>());
    max_off = std::max(max_off, off);
    // within the driver's 0.5 m (distance to the nearest piece; 1 mm for the closed form's
    // rounding)
    ASSERT_LE(off, kLateral_m + 1e-3) << t;
    // the heading is the direction of travel
    const Eigen::Vector2d dir(std::cos(s.yaw_rad), std::sin(s.yaw_rad));
    ASSERT_NEAR(dir.dot(s.velocity_enu_m_s.head<2>().normalized()), 1.0, kDirTol) << t;
    // the velocity is the derivative of the position
    const Eigen::Vector3d ahead = truck.state(t + 1e-4).position_enu_m;
    ASSERT_LT((ahead - s.position_enu_m - 1e-4 * s.velocity_enu_m_s).norm(), 1e-5) << t;
  }
  EXPECT_GT(max_off, 0.1);
  // a reset with the same seed replays the drive; another seed drives differently
  const Eigen::Vector3d at30 = truck.state(30.0).position_enu_m;
  sim->reset(4);
  EXPECT_EQ(truck.state(30.0).position_enu_m, at30);
  sim->reset(5);
  EXPECT_GT((truck.state(30.0).position_enu_m - at30).norm(), 0.01);
}

}  // namespace
}  // namespace uavsim::server::objects
