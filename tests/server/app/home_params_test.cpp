// Home and parameters from outside the code: the world's uavsim:home and uavsim:params texts, --home and
// --defaults files, applied to the flight controllers at start and again after a reset; bad entries name
// the file and line.
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include "app/param_file.hpp"
#include "app/server_app.hpp"
#include "physics/object_bodies.hpp"
#include "physics/world.hpp"
#include "sim/simulation.hpp"

namespace uavsim::server::app {
namespace {

const std::string kWorld = std::string(UAVSIM_TEST_DATA_DIR) + "/worlds/home_params.xml";

std::unique_ptr<physics::World> load_world() {
  physics::ComposeOptions o;
  o.models_dir = UAVSIM_MODELS_DIR;
  return physics::World::load(kWorld, o);
}

std::string write_file(const std::string& name, const std::string& text) {
  const std::string path = ::testing::TempDir() + name;
  std::ofstream(path) << text;
  return path;
}

std::vector<std::string> names_of(const physics::World& w) {
  std::vector<std::string> names;
  for (const physics::VehicleBinding& v : w.vehicles()) names.push_back(v.name);
  return names;
}

TEST(HomeParams, TheWorldsHomeUnlessHomeIsGiven) {
  const auto world = load_world();
  Options o;
  common::GeodeticOrigin h = world_home(*world, o);
  EXPECT_DOUBLE_EQ(h.lat_deg, -35.363261);
  EXPECT_DOUBLE_EQ(h.lon_deg, 149.165230);
  EXPECT_DOUBLE_EQ(h.alt_m, 584.0);
  o.home = HomeOption{47.0, 8.0, 400.0, 0.0};
  h = world_home(*world, o);
  EXPECT_DOUBLE_EQ(h.lat_deg, 47.0);
  EXPECT_DOUBLE_EQ(h.alt_m, 400.0);
}

TEST(HomeParams, WorldThenFilesApplyToTheFlightControllersAndSurviveAReset) {
  auto world = load_world();
  const std::string parm = write_file("d.parm", "# saved by a ground station\nRTL_ALT,3000\nANGLE_MAX\t2500\n");
  sim::SimConfig config;
  config.vehicle_params = vehicle_params(names_of(*world), physics::custom_texts(*world, "uavsim:params:"), {parm});
  sim::Simulation s(std::move(world), config);
  ASSERT_EQ(s.vehicle_count(), 7u);
  for (std::size_t i = 0; i < s.vehicle_count(); ++i) {
    EXPECT_EQ(s.fc(i).param("FS_GCS_ENABLE"), 1.0) << s.vehicle_name(i);
    EXPECT_EQ(s.fc(i).param("RTL_ALT"), 3000.0) << "the file comes after the world";
    EXPECT_EQ(s.fc(i).param("ANGLE_MAX"), 2500.0);
  }
  EXPECT_EQ(s.fc(0).param("WPNAV_SPEED"), 500.0);   // scout only
  EXPECT_EQ(s.fc(1).param("WPNAV_SPEED"), 1000.0);  // a swarm vehicle keeps the default
  s.reset(2);
  EXPECT_EQ(s.fc(0).param("WPNAV_SPEED"), 500.0);
  EXPECT_EQ(s.fc(3).param("RTL_ALT"), 3000.0);
}

TEST(HomeParams, BadEntriesNameTheFileAndLine) {
  auto expect_error = [](const std::string& text, const std::string& fragment) {
    try {
      parse_param_text(text, "my.parm");
      FAIL() << "accepted: " << text;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
    }
  };
  expect_error("RTL_ALT 1500\nNO_SUCH_PARAM 1\n", "my.parm:2: unknown parameter NO_SUCH_PARAM");
  expect_error("\n\nANGLE_MAX 99999\n", "my.parm:3: ANGLE_MAX 99999 is out of its range 1000 to 8000");
  expect_error("RTL_ALT\n", "my.parm:1");
  expect_error("RTL_ALT nan\n", "my.parm:1");
  EXPECT_EQ(parse_param_text("  # only a comment\n\n", "x").size(), 0u);
  EXPECT_THROW(read_param_file(::testing::TempDir() + "missing.parm"), std::invalid_argument);
  EXPECT_THROW(vehicle_params({"uav0"}, {{"uavsim:params:nobody", "RTL_ALT 2000"}}, {}), std::invalid_argument);
}

TEST(HomeParams, TheParameterDocIsUpToDate) {
  std::ifstream in(std::string(UAVSIM_SOURCE_DIR) + "/docs/parameters.md");
  ASSERT_TRUE(in) << "docs/parameters.md is missing: uavsim-server --list-params > docs/parameters.md";
  std::stringstream doc;
  doc << in.rdbuf();
  EXPECT_EQ(doc.str(), params_markdown())
      << "docs/parameters.md is stale: regenerate it with uavsim-server --list-params > docs/parameters.md";
  // every parameter has its meaning written down
  EXPECT_EQ(params_markdown().find(" |  |\n"), std::string::npos);
}

}  // namespace
}  // namespace uavsim::server::app
