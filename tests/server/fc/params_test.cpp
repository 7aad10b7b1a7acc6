#include "fc/params.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <set>

#include "fc/angles.hpp"
#include "fc/flight_controller.hpp"
#include "test_airframes.hpp"

namespace uavsim::server::fc {
namespace {

constexpr double kExactTol = 1e-12;

TEST(Params, GetAndSetKnownParameter) {
  FlightController fc(test::make_quad(), 1);
  EXPECT_EQ(fc.param("WPNAV_SPEED"), 1000.0);
  EXPECT_EQ(fc.set_param("WPNAV_SPEED", 500.0), CommandResult::kAccepted);
  EXPECT_EQ(fc.param("WPNAV_SPEED"), 500.0);
}

TEST(Params, UnknownNameIsInvalid) {
  FlightController fc(test::make_quad(), 1);
  EXPECT_FALSE(fc.param("NO_SUCH_PARAM").has_value());
  EXPECT_EQ(fc.set_param("NO_SUCH_PARAM", 1.0), CommandResult::kInvalid);
}

TEST(Params, NonFiniteAndOutOfRangeAreRejectedAndLeaveValue) {
  FlightController fc(test::make_quad(), 1);
  EXPECT_EQ(fc.set_param("ANGLE_MAX", std::numeric_limits<double>::quiet_NaN()), CommandResult::kInvalid);
  EXPECT_EQ(fc.set_param("ANGLE_MAX", std::numeric_limits<double>::infinity()), CommandResult::kInvalid);
  EXPECT_EQ(fc.set_param("ANGLE_MAX", 1e9), CommandResult::kInvalid);
  EXPECT_EQ(fc.param("ANGLE_MAX"), 3000.0);
}

TEST(Params, IntegerParametersKeepTheWholePartAsArduPilotStoresThem) {
  FlightController fc(test::make_quad(), 1);
  EXPECT_EQ(fc.param_kind("SYSID_THISMAV"), ParamKind::kInt16);
  EXPECT_EQ(fc.param_kind("PSC_POSXY_P"), ParamKind::kFloat);
  EXPECT_EQ(fc.set_param("SYSID_THISMAV", 1.7), CommandResult::kAccepted);
  EXPECT_EQ(fc.param("SYSID_THISMAV"), 1.0);
  // a float's rounding error below the whole number is not a step down: 3 - 2^-22 is 3
  EXPECT_EQ(fc.set_param("SYSID_THISMAV", 3.0 - std::ldexp(1.0, -22)), CommandResult::kAccepted);
  EXPECT_EQ(fc.param("SYSID_THISMAV"), 3.0);
  // the range is checked on what would be stored: 0.5 stores 0, below SYSID_THISMAV's minimum of 1
  EXPECT_EQ(fc.set_param("SYSID_THISMAV", 0.5), CommandResult::kInvalid);
  EXPECT_EQ(fc.param("SYSID_THISMAV"), 3.0);
  EXPECT_EQ(stored_value(ParamKind::kInt8, -2.7), -2.0);
  EXPECT_EQ(stored_value(ParamKind::kFloat, -2.7), -2.7);
}

TEST(Params, OrderIsStableAndNamesUnique) {
  FlightController a(test::make_quad(), 1), b(test::make_hexa(), 2);
  EXPECT_EQ(a.param_names(), b.param_names());
  const std::set<std::string> unique(a.param_names().begin(), a.param_names().end());
  EXPECT_EQ(unique.size(), a.param_names().size());
  // the first rows are part of the MAVLink contract (param_index)
  EXPECT_EQ(a.param_names()[0], "SYSID_THISMAV");
  EXPECT_EQ(a.param_names()[1], "PSC_POSXY_P");
  for (const std::string& n : a.param_names()) EXPECT_TRUE(a.param(n).has_value()) << n;
}

TEST(Params, BatteryCapacityComesFromAirframe) {
  FlightController fc(test::make_hexa(), 1);
  EXPECT_EQ(fc.param("BATT_CAPACITY"), 16000.0);
}

TEST(Params, DerivedValuesAreSi) {
  ParamTable t(5000.0);
  ASSERT_TRUE(t.set("WPNAV_SPEED", 750.0));
  EXPECT_DOUBLE_EQ(t.derived().wp_speed_m_s, 7.5);
  ASSERT_TRUE(t.set("ANGLE_MAX", 4500.0));
  EXPECT_NEAR(t.derived().angle_max_rad, kPi / 4.0, kExactTol);
  // RTL_SPEED 0 means WPNAV_SPEED, as ArduCopter
  EXPECT_DOUBLE_EQ(t.derived().rtl_speed_m_s, 7.5);
}

}  // namespace
}  // namespace uavsim::server::fc
