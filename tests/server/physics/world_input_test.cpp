// Bad numbers and runaway structure in world files: each is refused at once with the file and line.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "physics/world_composer.hpp"

namespace uavsim::server::physics {
namespace {

namespace fs = std::filesystem;

fs::path temp_dir() {
  const fs::path dir = fs::temp_directory_path() / "uavsim_world_input_test";
  fs::create_directories(dir);
  return dir;
}

std::string write_temp(const std::string& name, const std::string& text) {
  const fs::path p = temp_dir() / name;
  std::ofstream(p) << text;
  return p.string();
}

ComposeOptions options() {
  ComposeOptions o;
  o.models_dir = UAVSIM_MODELS_DIR;
  return o;
}

// a world with one line of worldbody content (on line 3)
std::string world_with(const std::string& name, const std::string& element) {
  return write_temp(name, "<mujoco><compiler angle=\"radian\"/>\n<worldbody>\n" + element + "\n</worldbody>\n</mujoco>\n");
}

// the WorldError's message, or "" when composing succeeded
std::string compose_error(const std::string& path) {
  try {
    compose_world(path, options());
  } catch (const WorldError& e) {
    return e.what();
  }
  return "";
}

void expect_error_at(const std::string& path, int line, const std::string& mentions) {
  const std::string what = compose_error(path);
  EXPECT_NE(what.find(path + ":" + std::to_string(line) + ":"), std::string::npos) << what;
  EXPECT_NE(what.find(mentions), std::string::npos) << what;
}

TEST(WorldInput, GridTooBigForTheVehicleCapOrForAnIntIsRefused) {
  // 65536 x 65537 once overflowed int past the cap and died in bad_alloc
  expect_error_at(world_with("grid_overflow.xml",
                             R"(<uavsim_grid type="quad" rows="65536" cols="65537" spacing="3"/>)"),
                  3, "rows");
  // within int, over the vehicle cap: says what to do instead
  expect_error_at(world_with("grid_5000.xml", R"(<uavsim_grid type="quad" rows="50" cols="100" spacing="3"/>)"),
                  3, "several servers");
  expect_error_at(world_with("grid_text.xml", R"(<uavsim_grid type="quad" rows="ten" cols="2"/>)"), 3, "rows");
  expect_error_at(world_with("grid_spacing.xml", R"(<uavsim_grid type="quad" rows="2" cols="2" spacing="nan"/>)"),
                  3, "spacing");
}

TEST(WorldInput, PositionsAndYawMustBeFiniteAndInRange) {
  // pos 1e300 made MuJoCo reset at t = 0 forever; yaw 1e308 made the state NaN; "nan" read as 0
  expect_error_at(world_with("pos_huge.xml", R"(<uavsim_vehicle type="quad" name="a" pos="1e300 0 0"/>)"), 3,
                  "pos");
  expect_error_at(world_with("pos_nan.xml", R"(<uavsim_vehicle type="quad" name="a" pos="nan 0 0"/>)"), 3, "pos");
  expect_error_at(world_with("pos_short.xml", R"(<uavsim_vehicle type="quad" name="a" pos="1 2"/>)"), 3, "pos");
  expect_error_at(world_with("pos_long.xml", R"(<uavsim_vehicle type="quad" name="a" pos="1 2 3 4"/>)"), 3,
                  "pos");
  expect_error_at(world_with("yaw_huge.xml", R"(<uavsim_vehicle type="quad" name="a" yaw_deg="1e308"/>)"), 3,
                  "yaw_deg");
  expect_error_at(world_with("yaw_inf.xml", R"(<uavsim_object type="balloon" name="b" yaw_deg="inf"/>)"), 3,
                  "yaw_deg");
  // good values still compose
  EXPECT_EQ(compose_error(world_with("good.xml", R"(<uavsim_vehicle type="quad" name="a" pos="1 2 0.5" yaw_deg="-90"/>)")),
            "");
}

TEST(WorldInput, IncludeFanOutIsStoppedByTheTotalNotTheDepth) {
  // 12 files, each including the next 8 times: 8^11 includes, all within the depth limit (16)
  for (int i = 0; i < 12; ++i) {
    std::string body;
    if (i < 11) {
      for (int k = 0; k < 8; ++k) body += "<include file=\"fan" + std::to_string(i + 1) + ".xml\"/>\n";
    }
    write_temp("fan" + std::to_string(i) + ".xml", "<mujoco>\n" + body + "</mujoco>\n");
  }
  const std::string path =
      write_temp("fan_world.xml", "<mujoco>\n<include file=\"fan0.xml\"/>\n<worldbody/>\n</mujoco>\n");
  const std::string what = compose_error(path);
  EXPECT_NE(what.find("includes more than"), std::string::npos) << what;
}

TEST(WorldInput, OverlongMeshPathNamesTheWorldFileAndLine) {
  const std::string long_name(5000, 'm');
  const std::string path = write_temp("long_mesh.xml", "<mujoco>\n<asset>\n<mesh name=\"m\" file=\"" + long_name +
                                                           ".stl\"/>\n</asset>\n<worldbody/>\n</mujoco>\n");
  const std::string what = compose_error(path);
  EXPECT_NE(what.find(path), std::string::npos) << what.substr(0, 300);
}

}  // namespace
}  // namespace uavsim::server::physics
