// The parts of the agent program and launcher that are pure: the APD report line (agent ->
// launcher) and the generated world.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

#include "apd_report.hpp"
#include "coverage_world.hpp"
#include "uavsim/common/angles.hpp"

namespace uavsim::missions::coverage {
namespace {

TEST(ApdReport, RoundTripsAndRoundsInwardsToCentimetres) {
  AreaParts apd(10);
  apd.add(0, {0.0, 12.345});
  apd.add(0, {20.001, 30.0});
  apd.add(7, {5.5, 99.999});
  const std::string line = encode_apd_report(3, 12.5, apd);
  EXPECT_EQ(line, "APD 3 12.500 0:0-1234,2001-3000;7:550-9999");
  const auto r = decode_apd_report(line, 10);
  ASSERT_TRUE(r);
  EXPECT_EQ(r->agent, 3);
  EXPECT_DOUBLE_EQ(r->time_s, 12.5);
  ASSERT_EQ(r->apd.stripe(0).size(), 2u);
  EXPECT_DOUBLE_EQ(r->apd.stripe(0)[0].end_m, 12.34);  // inwards: never claims more
  EXPECT_DOUBLE_EQ(r->apd.stripe(0)[1].start_m, 20.01);
  EXPECT_DOUBLE_EQ(r->apd.stripe(7)[0].end_m, 99.99);
  EXPECT_TRUE(r->apd.stripe(1).empty());
}

TEST(ApdReport, AnEmptyDatabaseIsADash) {
  const std::string line = encode_apd_report(0, 1.0, AreaParts(4));
  EXPECT_EQ(line, "APD 0 1.000 -");
  const auto r = decode_apd_report(line, 4);
  ASSERT_TRUE(r);
  EXPECT_DOUBLE_EQ(r->apd.covered_fraction(10.0), 0.0);
}

TEST(ApdReport, MalformedLinesAreRejected) {
  for (const char* bad : {"", "APD", "APD x 1 -", "APD 1 1 12:0-100", "APD 1 1 0:100-50",
                          "APD 1 1 0:", "APD 1 1 0:1-2x", "agent 1 t=2 state Running leader 0",
                          "APD -1 1 -", "APD 1 1 0:-5-10"}) {
    EXPECT_FALSE(decode_apd_report(bad, 10)) << bad;
  }
}

TEST(CoverageWorld, QuadsOnATakeOffLineBeforeTheRectangle) {
  WorldSpec s;
  s.agents = 3;
  ASSERT_EQ(s.validate(), "");
  const std::string xml = coverage_world_xml(s);
  // agent i at (origin_x - 10, origin_y + 7 i)
  EXPECT_NE(
      xml.find(
          R"(<uavsim_vehicle type="quad" name="uav0" pos="-10.000 0.000 0" collision="lean"/>)"),
      std::string::npos)
      << xml;
  EXPECT_NE(xml.find(R"(name="uav2" pos="-10.000 14.000 0")"), std::string::npos) << xml;
  EXPECT_EQ(xml.find("uav3"), std::string::npos);
  // the ground holds the rectangle with a 50 m margin: x in [-60, 200], y in [-50, 150]
  EXPECT_NE(xml.find(R"(pos="70.000 50.000 0" size="130.000 100.000 0.1")"), std::string::npos)
      << xml;
}

// coverage-run's video: the world's camera "overview" looks straight down (north up) and sees the
// whole rectangle and the take-off line, on the ground and at the flock's 20-30 m
TEST(CoverageWorld, OverviewCameraSeesTheRectangleAndTheTakeOffLine) {
  WorldSpec s;
  s.agents = 5;
  const std::string xml = coverage_world_xml(s);
  const size_t at = xml.find(R"(<camera name="overview" pos=")");
  ASSERT_NE(at, std::string::npos) << xml;
  double cx = 0, cy = 0, cz = 0;
  ASSERT_EQ(
      std::sscanf(xml.c_str() + at, R"(<camera name="overview" pos="%lf %lf %lf")", &cx, &cy, &cz),
      3);
  EXPECT_NE(xml.find(R"(xyaxes="1 0 0 0 1 0" fovy="45")", at), std::string::npos);
  // 640 x 480 at fovy 45 deg: f = 240 / tan(22.5 deg) = 579.4 px; x east, y south in the image
  const double f_px = 240.0 / std::tan(22.5 * common::kPi / 180.0);
  for (const double z : {0.0, 20.0, 30.0}) {
    for (const auto& [x, y] : std::vector<std::pair<double, double>>{
             {0, 0}, {150, 0}, {0, 100}, {150, 100}, {-10, 0}, {-10, 40}}) {
      const double u = 319.5 + f_px * (x - cx) / (cz - z);
      const double v = 239.5 - f_px * (y - cy) / (cz - z);
      EXPECT_TRUE(u > 0 && u < 640 && v > 0 && v < 480)
          << x << " " << y << " " << z << ": " << u << " " << v;
    }
  }
  // the outline: four drawn-only boxes
  for (const char* side : {"area_s", "area_n", "area_w", "area_e"}) {
    const size_t g = xml.find(std::string("name=\"") + side + "\"");
    ASSERT_NE(g, std::string::npos) << side;
    EXPECT_NE(xml.find(R"(contype="0" conaffinity="0")", g), std::string::npos) << side;
  }
}

TEST(CoverageWorld, OutOfRangeNumbersAreRefusedByName) {
  auto refused = [](void (*edit)(WorldSpec&), const char* word) {
    WorldSpec s;
    edit(s);
    const std::string why = s.validate();
    EXPECT_NE(why.find(word), std::string::npos) << why;
  };
  refused([](WorldSpec& s) { s.agents = 0; }, "agents");
  refused([](WorldSpec& s) { s.agents = 65; }, "agents");
  refused([](WorldSpec& s) { s.length_x_m = 1e9; }, "length");
  refused([](WorldSpec& s) { s.width_y_m = std::nan(""); }, "width");
  refused([](WorldSpec& s) { s.line_spacing_m = 0.5; }, "line_spacing_m");
  refused([](WorldSpec& s) { s.origin_x_m = -1e6; }, "origin");
  refused([](WorldSpec& s) { s.land_speed_m_s = 0.2; }, "land_speed_m_s");
  refused([](WorldSpec& s) { s.land_speed_high_m_s = 6.0; }, "land_speed_high_m_s");
}

// the autopilots land the flock at 1 m/s below 10 m and 3 m/s above (ArduCopter's LAND_SPEED and
// LAND_SPEED_HIGH, cm/s), every quad: the world's uavsim:params:* text
TEST(CoverageWorld, EveryQuadLandsAtTheSpecsDescentSpeeds) {
  WorldSpec s;
  EXPECT_NE(coverage_world_xml(s).find(
                R"(<text name="uavsim:params:*" data="LAND_SPEED 100; LAND_SPEED_HIGH 300"/>)"),
            std::string::npos);
  s.land_speed_m_s = 0.5;
  s.land_speed_high_m_s = 0.0;  // ArduCopter: WPNAV_SPEED_DN instead
  EXPECT_NE(coverage_world_xml(s).find(R"(data="LAND_SPEED 50; LAND_SPEED_HIGH 0")"),
            std::string::npos);
}

}  // namespace
}  // namespace uavsim::missions::coverage
