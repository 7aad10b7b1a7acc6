// Meshes in worlds: a world that references a COLLADA mesh (which MuJoCo 2.2 cannot read) loads, the
// composer having converted it into the mesh cache; a second load reuses the converted file.
#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <string>

#include "physics/world.hpp"
#include "physics/world_composer.hpp"

namespace uavsim::server::physics {
namespace {

namespace fs = std::filesystem;

constexpr double kSizeTol_m = 1e-6;  // float32 vertices
constexpr double kMassTol_kg = 1e-3;

// a 0.4 x 0.6 x 0.2 m box centred on the origin, six quads, z up
constexpr const char* kBoxDae = R"(<?xml version="1.0" encoding="utf-8"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
  <asset><unit name="meter" meter="1"/><up_axis>Z_UP</up_axis></asset>
  <library_geometries>
    <geometry id="box" name="box"><mesh>
      <source id="box-pos">
        <float_array id="box-pos-array" count="24">
          -0.2 -0.3 -0.1  0.2 -0.3 -0.1  0.2 0.3 -0.1  -0.2 0.3 -0.1
          -0.2 -0.3 0.1  0.2 -0.3 0.1  0.2 0.3 0.1  -0.2 0.3 0.1
        </float_array>
        <technique_common><accessor source="#box-pos-array" count="8" stride="3">
          <param name="X" type="float"/><param name="Y" type="float"/><param name="Z" type="float"/>
        </accessor></technique_common>
      </source>
      <vertices id="box-vtx"><input semantic="POSITION" source="#box-pos"/></vertices>
      <polylist count="6">
        <input semantic="VERTEX" source="#box-vtx" offset="0"/>
        <vcount>4 4 4 4 4 4</vcount>
        <p>0 3 2 1  4 5 6 7  0 1 5 4  2 3 7 6  0 4 7 3  1 2 6 5</p>
      </polylist>
    </mesh></geometry>
  </library_geometries>
  <library_visual_scenes>
    <visual_scene id="scene" name="scene">
      <node id="box-node" name="box"><instance_geometry url="#box"/></node>
    </visual_scene>
  </library_visual_scenes>
  <scene><instance_visual_scene url="#scene"/></scene>
</COLLADA>
)";

// the mesh by a path relative to the world file (through meshdir), unnamed: MuJoCo names it "box"
constexpr const char* kWorld = R"(<mujoco>
  <compiler meshdir="meshes"/>
  <asset><mesh file="box.dae"/></asset>
  <worldbody>
    <body name="crate" pos="0 0 1"><freejoint/><geom name="crate_geom" type="mesh" mesh="box"/></body>
  </worldbody>
</mujoco>
)";

class WorldMesh : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::path(::testing::TempDir()) / "world_mesh_test";
    fs::remove_all(dir_);
    fs::create_directories(dir_ / "meshes");
    std::ofstream(dir_ / "meshes" / "box.dae") << kBoxDae;
    std::ofstream(dir_ / "world.xml") << kWorld;
    options_.models_dir = UAVSIM_MODELS_DIR;
    options_.mesh_cache_dir = (dir_ / "cache").string();
  }
  std::vector<fs::path> cached_files() const {
    std::vector<fs::path> files;
    if (!fs::exists(options_.mesh_cache_dir)) return files;
    for (const auto& e : fs::directory_iterator(options_.mesh_cache_dir)) files.push_back(e.path());
    return files;
  }
  std::string world() const { return (dir_ / "world.xml").string(); }

  fs::path dir_;
  ComposeOptions options_;
};

// the mesh geom's size: MuJoCo fits a box of the mesh's inertia, which for a box mesh is the box
// itself, half sizes 0.2, 0.3, 0.1 m (in the order of the inertia's principal axes, so compared sorted)
std::array<double, 3> sorted_geom_size(const World& w, const char* geom) {
  const mjModel* m = w.model();
  const int id = mj_name2id(m, mjOBJ_GEOM, geom);
  EXPECT_GE(id, 0);
  EXPECT_EQ(m->geom_type[id], mjGEOM_MESH);
  std::array<double, 3> s = {m->geom_size[3 * id], m->geom_size[3 * id + 1], m->geom_size[3 * id + 2]};
  std::sort(s.begin(), s.end());
  return s;
}

TEST_F(WorldMesh, ColladaMeshIsConvertedAndLoadsWithItsSize) {
  const auto w = World::load(world(), options_);
  const std::array<double, 3> s = sorted_geom_size(*w, "crate_geom");
  EXPECT_NEAR(s[0], 0.1, kSizeTol_m);
  EXPECT_NEAR(s[1], 0.2, kSizeTol_m);
  EXPECT_NEAR(s[2], 0.3, kSizeTol_m);
  // mass at MuJoCo's default density: 1000 kg/m^3 * 0.4 * 0.6 * 0.2 m^3 = 48 kg
  const mjModel* m = w->model();
  EXPECT_NEAR(m->body_mass[mj_name2id(m, mjOBJ_BODY, "crate")], 48.0, kMassTol_kg);
  // the composed world points at the one converted file in the cache
  const std::vector<fs::path> files = cached_files();
  ASSERT_EQ(files.size(), 1u);
  EXPECT_EQ(files[0].extension(), ".obj");
  EXPECT_EQ(files[0].filename().string().rfind("box-", 0), 0u) << files[0];
  EXPECT_NE(compose_world(world(), options_).find(files[0].string()), std::string::npos);
}

TEST_F(WorldMesh, SecondLoadReusesTheConvertedFile) {
  World::load(world(), options_);
  std::vector<fs::path> files = cached_files();
  ASSERT_EQ(files.size(), 1u);
  // date the cached file back: a reconversion would write it again and move its time to now
  const auto old_time = fs::file_time_type::clock::now() - std::chrono::hours(24);
  fs::last_write_time(files[0], old_time);
  const auto w = World::load(world(), options_);
  EXPECT_NEAR(sorted_geom_size(*w, "crate_geom")[2], 0.3, kSizeTol_m);
  files = cached_files();
  ASSERT_EQ(files.size(), 1u);
  EXPECT_EQ(fs::last_write_time(files[0]), old_time);
}

TEST_F(WorldMesh, ChangedContentGetsANewCacheEntry) {
  World::load(world(), options_);
  std::string dae = kBoxDae;
  dae.replace(dae.find("0.2 0.3 0.1  -0.2 0.3 0.1"), 25, "0.2 0.3 0.5  -0.2 0.3 0.5");
  std::ofstream(dir_ / "meshes" / "box.dae") << dae;
  World::load(world(), options_);
  EXPECT_EQ(cached_files().size(), 2u);
}

TEST_F(WorldMesh, UnreadableMeshFailsNamingTheWorldAndTheMesh) {
  std::ofstream(dir_ / "meshes" / "box.dae") << "not a mesh at all";
  try {
    World::load(world(), options_);
    FAIL() << "loaded an unreadable mesh";
  } catch (const WorldError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(world()), std::string::npos) << what;
    EXPECT_NE(what.find("box.dae"), std::string::npos) << what;
  }
  EXPECT_TRUE(cached_files().empty());
}

TEST_F(WorldMesh, MissingMeshFailsNamingTheWorldAndTheMesh) {
  fs::remove(dir_ / "meshes" / "box.dae");
  try {
    World::load(world(), options_);
    FAIL() << "loaded a missing mesh";
  } catch (const WorldError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(world()), std::string::npos) << what;
    EXPECT_NE(what.find("box.dae"), std::string::npos) << what;
  }
}

TEST_F(WorldMesh, AMeshPathThatIsADirectorySaysSo) {
  // it used to fail as "no vertices", from MuJoCo reading the directory as an empty mesh
  for (const char* name : {"box.dae", "box.stl"}) {
    fs::remove_all(dir_ / "meshes" / name);
    fs::create_directories(dir_ / "meshes" / name);
    std::string xml = kWorld;
    xml.replace(xml.find("box.dae"), 7, name);
    std::ofstream(dir_ / "world.xml") << xml;
    try {
      World::load(world(), options_);
      FAIL() << "loaded a directory as a mesh";
    } catch (const WorldError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find(name), std::string::npos) << what;
      EXPECT_NE(what.find("is a directory"), std::string::npos) << what;
    }
  }
}

}  // namespace
}  // namespace uavsim::server::physics
