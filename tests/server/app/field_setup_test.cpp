// The field conditions of a run (app/field_setup.hpp): --realism over the world's uavsim:realism,
// the world's numerics over the level's defaults, --wind over both; bad values refused with their
// names.
#include "app/field_setup.hpp"

#include <gtest/gtest.h>

#include <fstream>

#include "uavsim/common/angles.hpp"

namespace uavsim::server::app {
namespace {

constexpr double kExactTol = 1e-12;

std::unique_ptr<physics::World> world_with(const std::string& label, const std::string& custom) {
  const std::string path = ::testing::TempDir() + "/uavsim_field_" + label + ".xml";
  std::ofstream(path)
      << "<mujoco model=\"" << label << "\">\n"
      << "  <compiler angle=\"radian\"/>\n"
      << "  <include file=\"" << UAVSIM_MODELS_DIR << "/common/ground.xml\"/>\n"
      << "  <worldbody><uavsim_vehicle type=\"quad\" name=\"uav0\" pos=\"0 0 0\"/></worldbody>\n"
      << "  <custom>\n"
      << custom << "\n  </custom>\n</mujoco>\n";
  physics::ComposeOptions o;
  o.models_dir = UAVSIM_MODELS_DIR;
  return physics::World::load(path, o);
}

Options parsed(std::vector<std::string> args) {
  args.insert(args.begin(), "w.xml");
  ParseResult r = parse_args(args, [](const std::string&) { return std::nullopt; });
  EXPECT_TRUE(r.options) << r.error;
  return r.options.value_or(Options{});
}

TEST(FieldSetup, IdealByDefaultFieldBySwitch) {
  auto w = world_with("plain", "<numeric name=\"uavsim:unused\" data=\"0\"/>");
  const sim::FieldConditions ideal = resolve_field_conditions(parsed({}), *w);
  EXPECT_EQ(ideal.realism, sim::Realism::kIdeal);
  EXPECT_FALSE(ideal.wind.active());
  EXPECT_TRUE(ideal.sensor_params.empty());
  EXPECT_TRUE(ideal.camera_settings.empty());
  EXPECT_EQ(ideal.gimbal.time_const_s, 0.0);
  EXPECT_EQ(ideal.battery_resistance_ohm, 0.0);
  EXPECT_FALSE(ideal.balloons.sway);

  const sim::FieldConditions field = resolve_field_conditions(parsed({"--realism", "field"}), *w);
  EXPECT_EQ(field.realism, sim::Realism::kField);
  EXPECT_GT(field.wind.speed_m_s, 0.0);
  EXPECT_TRUE(field.wind_from_seeded);
  EXPECT_FALSE(field.sensor_params.empty());
  EXPECT_FALSE(field.camera_settings.empty());
  EXPECT_GT(field.gimbal.time_const_s, 0.0);
  EXPECT_GT(field.battery_resistance_ohm, 0.0);
  EXPECT_TRUE(field.balloons.sway);
}

TEST(FieldSetup, WorldSettingsThenCommandLine) {
  auto w = world_with("field", R"(<text name="uavsim:realism" data="field"/>
    <numeric name="uavsim:wind" data="7 45 2"/>
    <numeric name="uavsim:gimbal_dynamics" data="0.1 90"/>
    <numeric name="uavsim:balloon_variation" data="0.3 0"/>
    <numeric name="uavsim:battery_sag" data="0.02"/>)");
  sim::FieldConditions c = resolve_field_conditions(parsed({}), *w);
  EXPECT_EQ(c.realism, sim::Realism::kField);
  EXPECT_EQ(c.wind.speed_m_s, 7.0);
  EXPECT_EQ(c.wind.from_deg, 45.0);
  EXPECT_FALSE(c.wind_from_seeded);
  EXPECT_EQ(c.wind.turbulence_sd_m_s, 2.0);
  EXPECT_EQ(c.gimbal.time_const_s, 0.1);
  EXPECT_NEAR(c.gimbal.rate_max_rad_s, common::kPi / 2, kExactTol);
  EXPECT_EQ(c.balloons.height_spread_m, 0.3);
  EXPECT_FALSE(c.balloons.sway);
  EXPECT_EQ(c.battery_resistance_ohm, 0.02);
  // --wind replaces the world's mean wind; --realism ideal turns the level's defaults off, the
  // world's own settings stay
  c = resolve_field_conditions(parsed({"--wind", "3,180", "--realism", "ideal"}), *w);
  EXPECT_EQ(c.realism, sim::Realism::kIdeal);
  EXPECT_EQ(c.wind.speed_m_s, 3.0);
  EXPECT_EQ(c.wind.from_deg, 180.0);
  EXPECT_EQ(c.wind.turbulence_sd_m_s, 2.0);
  EXPECT_TRUE(c.sensor_params.empty());
}

TEST(FieldSetup, BadWorldValuesNameTheirAttribute) {
  auto expect_error = [](const std::string& label, const std::string& custom,
                         const std::string& name) {
    auto w = world_with(label, custom);
    try {
      resolve_field_conditions(parsed({}), *w);
      ADD_FAILURE() << "accepted " << custom;
    } catch (const physics::WorldError& e) {
      EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
    }
  };
  expect_error("bad_level", R"(<text name="uavsim:realism" data="harsh"/>)", "uavsim:realism");
  expect_error("bad_wind", R"(<numeric name="uavsim:wind" data="-3 0"/>)", "uavsim:wind");
  expect_error("short_wind", R"(<numeric name="uavsim:wind" data="3"/>)", "uavsim:wind");
  expect_error("bad_spread", R"(<numeric name="uavsim:balloon_variation" data="2"/>)",
               "uavsim:balloon_variation");
  expect_error("bad_sag", R"(<numeric name="uavsim:battery_sag" data="-1"/>)",
               "uavsim:battery_sag");
}

TEST(FieldSetup, OptionsParseWindAndRealism) {
  const Options o = parsed({"--wind", "5,270,1.5", "--realism", "field"});
  ASSERT_TRUE(o.wind);
  EXPECT_EQ(o.wind->speed_m_s, 5.0);
  EXPECT_EQ(o.wind->from_deg, 270.0);
  EXPECT_EQ(o.wind->turbulence_sd_m_s.value_or(-1), 1.5);
  EXPECT_EQ(o.realism.value_or(""), "field");
  for (const char* bad : {"5", "5,", "-1,0", "5,0,99", "a,b", "5,0,1,2"}) {
    ParseResult r =
        parse_args({"w.xml", "--wind", bad}, [](const std::string&) { return std::nullopt; });
    EXPECT_FALSE(r.options) << bad;
    EXPECT_NE(r.error.find("--wind"), std::string::npos) << r.error;
  }
  ParseResult r =
      parse_args({"w.xml", "--realism", "harsh"}, [](const std::string&) { return std::nullopt; });
  EXPECT_FALSE(r.options);
  EXPECT_NE(r.error.find("--realism"), std::string::npos) << r.error;
}

}  // namespace
}  // namespace uavsim::server::app
