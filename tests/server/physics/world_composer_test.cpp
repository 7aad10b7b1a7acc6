#include "physics/world_composer.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <set>
#include <string>

#include "physics/world.hpp"

#include <mujoco/mujoco.h>

namespace uavsim::server::physics {
namespace {

constexpr double kPosTol_m = 1e-9;
constexpr double kDirTol = 1e-9;
// the soft contact lets the skids sink a few millimetres
constexpr double kSkidRestTol_m = 0.005;

namespace fs = std::filesystem;

// writes text into a fresh file under the test's temp dir and returns its path
std::string write_temp(const std::string& name, const std::string& text) {
  const fs::path dir = fs::temp_directory_path() / "uavsim_composer_test";
  fs::create_directories(dir);
  const fs::path p = dir / name;
  std::ofstream(p) << text;
  return p.string();
}

ComposeOptions options() {
  ComposeOptions o;
  o.models_dir = UAVSIM_MODELS_DIR;
  return o;
}

TEST(WorldComposer, MalformedXmlNamesFileAndLine) {
  const std::string path = write_temp("malformed.xml", "<mujoco>\n<worldbody>\n<body>\n</worldbody>\n");
  try {
    compose_world(path, options());
    FAIL() << "expected WorldError";
  } catch (const WorldError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(path), std::string::npos) << what;
    EXPECT_NE(what.find(":3:"), std::string::npos) << what;  // the <body> left open
  }
}

TEST(WorldComposer, UnknownVehicleTypeNamesFileLineAndKnownTypes) {
  const std::string path = write_temp("unknown.xml", R"(<mujoco>
  <compiler angle="radian"/>
  <worldbody>
    <uavsim_vehicle type="octo" name="uav0"/>
  </worldbody>
</mujoco>)");
  try {
    compose_world(path, options());
    FAIL() << "expected WorldError";
  } catch (const WorldError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(path + ":4:"), std::string::npos) << what;
    EXPECT_NE(what.find("octo"), std::string::npos) << what;
    EXPECT_NE(what.find("quad"), std::string::npos) << what;  // lists the known types
  }
}

TEST(WorldComposer, DuplicateNameIsRejected) {
  const std::string path = write_temp("dup.xml", R"(<mujoco>
  <compiler angle="radian"/>
  <worldbody>
    <uavsim_vehicle type="quad" name="a"/>
    <uavsim_vehicle type="hexa" name="a" pos="3 0 0"/>
  </worldbody>
</mujoco>)");
  EXPECT_THROW(compose_world(path, options()), WorldError);
}

TEST(WorldComposer, AngleUnitMismatchIsExplained) {
  const std::string path = write_temp("degree.xml", R"(<mujoco>
  <worldbody><uavsim_vehicle type="quad" name="a"/></worldbody>
</mujoco>)");
  try {
    compose_world(path, options());
    FAIL() << "expected WorldError";
  } catch (const WorldError& e) {
    EXPECT_NE(std::string(e.what()).find("angle"), std::string::npos) << e.what();
  }
}

TEST(WorldComposer, NestedUavsimElementIsAnError) {
  const std::string path = write_temp("nested.xml", R"(<mujoco>
  <compiler angle="radian"/>
  <worldbody><body name="b"><uavsim_vehicle type="quad" name="a"/></body></worldbody>
</mujoco>)");
  EXPECT_THROW(compose_world(path, options()), WorldError);
}

TEST(WorldComposer, GridMakesRowsTimesColsVehiclesWithPrefixedNames) {
  const std::string path = write_temp("grid.xml", R"(<mujoco>
  <compiler angle="radian"/>
  <worldbody>
    <geom name="ground" type="plane" size="50 50 0.1"/>
    <uavsim_grid type="quad" prefix="q" rows="2" cols="3" spacing="5" pos="1 2 0"/>
    <uavsim_vehicle type="hexa" name="big" pos="-10 0 0" yaw_deg="90"/>
  </worldbody>
</mujoco>)");
  auto world = World::load(path, options());
  ASSERT_EQ(world->vehicles().size(), 7u);
  EXPECT_EQ(world->vehicles()[0].name, "q0");
  EXPECT_EQ(world->vehicles()[5].name, "q5");
  EXPECT_EQ(world->vehicles()[6].name, "big");
  EXPECT_EQ(world->vehicles()[6].airframe.frame, "hexa");
  EXPECT_EQ(world->vehicles()[6].airframe.rotors.size(), 6u);
  // q4 is row 1, col 1: (1 + 5, 2 + 5); the template's own z offset (0.16 m) is kept
  const auto t = world->truth(4);
  EXPECT_NEAR(t.position_enu_m.x(), 6.0, kPosTol_m);
  EXPECT_NEAR(t.position_enu_m.y(), 7.0, kPosTol_m);
  EXPECT_NEAR(t.position_enu_m.z(), 0.16, kPosTol_m);
  // yaw 90 deg: body x points north (ENU y)
  const Eigen::Vector3d x_enu = world->truth(6).q_enu_body * Eigen::Vector3d::UnitX();
  EXPECT_NEAR(x_enu.y(), 1.0, kDirTol);
  EXPECT_GE(world->body_id("q3"), 0);
  const std::string mjcf = compose_world(path, options());
  EXPECT_NE(mjcf.find("\"q3/hull\""), std::string::npos);  // names inside templates are prefixed
}

// collidable geoms of vehicle v by local name ("hull", "gear_left", ...)
std::set<std::string> collidable_geoms(const World& world, const std::string& vehicle) {
  std::set<std::string> out;
  const mjModel* m = world.model();
  for (int g = 0; g < m->ngeom; ++g) {
    const std::string name = world.geom_name(g);
    if (name.rfind(vehicle + "/", 0) != 0) continue;
    if (m->geom_contype[g] != 0 || m->geom_conaffinity[g] != 0) out.insert(name.substr(vehicle.size() + 1));
  }
  return out;
}

TEST(WorldComposer, CollisionSetKeepsOnlyTheNamedGeomsCollidable) {
  const std::string path = write_temp("collision_sets.xml", R"(<mujoco>
  <compiler angle="radian"/>
  <worldbody>
    <geom name="ground" type="plane" size="50 50 0.1"/>
    <uavsim_vehicle type="quad" name="full" pos="0 0 0"/>
    <uavsim_vehicle type="quad" name="lean" pos="5 0 0" collision="lean"/>
    <uavsim_vehicle type="quad" name="popper" pos="10 0 0" collision="lean blade"/>
    <uavsim_grid type="quad" prefix="flock" rows="1" cols="2" spacing="4" pos="0 10 0" collision="hull gear"/>
  </worldbody>
</mujoco>)");
  auto world = World::load(path, options());
  // they start parked on the ground (their geoms then touch only what moves): awake, as composed
  for (size_t v = 0; v < world->vehicles().size(); ++v) world->wake(v);
  // the quad template: hull, 4 prop discs, 2 skids, 5 blades collide (12 geoms)
  const std::set<std::string> full = collidable_geoms(*world, "full");
  EXPECT_EQ(full.size(), 12u);
  EXPECT_TRUE(full.count("prop0") && full.count("blade4") && full.count("gear_left"));
  const std::set<std::string> lean = {"hull", "gear_left", "gear_right"};
  EXPECT_EQ(collidable_geoms(*world, "lean"), lean);
  EXPECT_EQ(collidable_geoms(*world, "flock0"), lean);
  EXPECT_EQ(collidable_geoms(*world, "flock1"), lean);
  std::set<std::string> popper = lean;
  for (int k = 0; k < 5; ++k) popper.insert("blade" + std::to_string(k));
  EXPECT_EQ(collidable_geoms(*world, "popper"), popper);
  // the blades keep their own bits (2: balloons only), the hull its 1
  const mjModel* m = world->model();
  EXPECT_EQ(m->geom_conaffinity[mj_name2id(m, mjOBJ_GEOM, "popper/blade0")], 2);
  EXPECT_EQ(m->geom_conaffinity[mj_name2id(m, mjOBJ_GEOM, "popper/hull")], 1);
}

TEST(WorldComposer, LeanQuadsStillRestOnTheirGear) {
  const std::string path = write_temp("lean_rest.xml", R"(<mujoco>
  <compiler angle="radian"/>
  <worldbody>
    <geom name="ground" type="plane" size="50 50 0.1"/>
    <uavsim_vehicle type="quad" name="uav0" pos="0 0 0.05" collision="lean"/>
  </worldbody>
</mujoco>)");
  auto world = World::load(path, options());
  for (int i = 0; i < 1000; ++i) world->step();
  // dropped 5 cm, it stands on its skids: the body origin 0.16 m up (gear bottom 0.15 + 0.01 below it),
  // less the soft contact's few millimetres
  EXPECT_NEAR(world->truth(0).position_enu_m.z(), 0.16, kSkidRestTol_m);
  EXPECT_LT(world->truth(0).velocity_enu_m_s.norm(), 0.01);
}

TEST(WorldComposer, BadCollisionSetNamesFileLineAndTheGeoms) {
  const struct {
    const char* value;
    const char* says;
  } cases[] = {
      {"", "must be full, lean"},
      {"hull wing gear", "'wing' names no geom"},
      {"hull prop", "leaves out the landing gear"},
      {"lean full", "'full' names no geom"},
  };
  for (const auto& c : cases) {
    const std::string path = write_temp("bad_collision.xml", std::string(R"(<mujoco>
  <compiler angle="radian"/>
  <worldbody>
    <uavsim_grid type="quad" rows="1" cols="2" collision=")") + c.value + R"("/>
  </worldbody>
</mujoco>)");
    try {
      compose_world(path, options());
      ADD_FAILURE() << "collision=\"" << c.value << "\" was accepted";
    } catch (const WorldError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find(path + ":4:"), std::string::npos) << what;
      EXPECT_NE(what.find(c.says), std::string::npos) << what;
    }
  }
  // on an object it is an error too
  const std::string path = write_temp("object_collision.xml", R"(<mujoco>
  <compiler angle="radian"/>
  <worldbody>
    <uavsim_object type="balloon" name="b" collision="lean"/>
  </worldbody>
</mujoco>)");
  EXPECT_THROW(compose_world(path, options()), WorldError);
}

TEST(WorldComposer, IncludeIsInlinedRelativeToTheIncludingFile) {
  fs::create_directories(fs::temp_directory_path() / "uavsim_composer_test" / "sub");
  write_temp("sub/part.xml", R"(<mujoco><worldbody><geom name="from_include" type="sphere" size="1"/></worldbody></mujoco>)");
  const std::string path = write_temp("with_include.xml", R"(<mujoco>
  <compiler angle="radian"/>
  <worldbody><include file="sub/part.xml"/></worldbody>
</mujoco>)");
  const std::string mjcf = compose_world(path, options());
  EXPECT_NE(mjcf.find("from_include"), std::string::npos);
  EXPECT_EQ(mjcf.find("<include"), std::string::npos);
}

TEST(WorldComposer, MissingIncludeNamesTheIncludingFile) {
  const std::string path = write_temp("bad_include.xml", R"(<mujoco>
  <worldbody><include file="nope.xml"/></worldbody>
</mujoco>)");
  try {
    compose_world(path, options());
    FAIL();
  } catch (const WorldError& e) {
    EXPECT_NE(std::string(e.what()).find(path + ":2:"), std::string::npos) << e.what();
  }
}

TEST(WorldComposer, AWorldOfOnesOwnIncludesTheShippedPartsFromAnywhere) {
  // a copy of a shipped world's include (file="../common/ground.xml") and the parts' place in the
  // models (file="common/ground.xml") both resolve, in a folder far from models/
  const fs::path dir = fs::temp_directory_path() / "uavsim_composer_test" / "elsewhere" / "mine";
  fs::create_directories(dir);
  for (const std::string inc : {"../common/ground.xml", "common/ground.xml"}) {
    const fs::path path = dir / "mine.xml";
    std::ofstream(path) << R"(<mujoco>
  <compiler angle="radian"/>
  <include file=")" << inc
                        << R"("/>
  <worldbody><uavsim_vehicle type="quad" name="uav0" pos="0 0 0"/></worldbody>
</mujoco>)";
    ASSERT_FALSE(fs::exists(dir / inc));  // not beside the world: only the models have it
    const std::string mjcf = compose_world(path.string(), options());
    EXPECT_NE(mjcf.find("name=\"ground\""), std::string::npos) << inc;
    EXPECT_EQ(World::from_mjcf(mjcf, "mine")->vehicles().size(), 1u) << inc;
  }
}

TEST(WorldComposer, AnIncludeBesideTheWorldComesBeforeTheShippedOne) {
  // the world's own common/ground.xml, not the shipped one
  fs::create_directories(fs::temp_directory_path() / "uavsim_composer_test" / "common");
  write_temp(
      "common/ground.xml",
      R"(<mujoco><worldbody><geom name="my_ground" type="plane" size="5 5 0.1"/></worldbody></mujoco>)");
  const std::string path = write_temp("own_ground.xml", R"(<mujoco>
  <compiler angle="radian"/>
  <include file="common/ground.xml"/>
  <worldbody/>
</mujoco>)");
  const std::string mjcf = compose_world(path, options());
  EXPECT_NE(mjcf.find("my_ground"), std::string::npos);
  EXPECT_EQ(mjcf.find("name=\"ground\""), std::string::npos);
}

TEST(WorldComposer, AMissingIncludeNamesEveryPlaceLookedIn) {
  const std::string path = write_temp("bad_include2.xml", R"(<mujoco>
  <worldbody><include file="parts/nope.xml"/></worldbody>
</mujoco>)");
  try {
    compose_world(path, options());
    FAIL();
  } catch (const WorldError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(path + ":2:"), std::string::npos) << what;
    EXPECT_NE(
        what.find((fs::path(UAVSIM_MODELS_DIR) / "parts/nope.xml").lexically_normal().string()),
        std::string::npos)
        << what;
  }
}

TEST(WorldComposer, ComposedTextLoadsFromAnywhere) {
  const std::string mjcf =
      compose_world(std::string(UAVSIM_MODELS_DIR) + "/worlds/empty.xml", options());
  auto world = World::from_mjcf(mjcf, "composed");
  EXPECT_EQ(world->vehicles().size(), 1u);
}

}  // namespace
}  // namespace uavsim::server::physics
