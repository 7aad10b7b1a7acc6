#include "assets/mesh_convert.hpp"

#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include <array>
#include <filesystem>
#include <fstream>
#include <memory>
#include <set>
#include <stdexcept>
#include <string>

namespace uavsim::server::assets {
namespace {

namespace fs = std::filesystem;

constexpr double kCoordTol = 1e-6;  // float32 storage in MuJoCo and STL
constexpr double kMassRelTol = 1e-5;
constexpr double kVolumeTol = 1e-8;  // m^3; assimp stores coordinates as float32

// A COLLADA scene with two geometries in three nodes:
//   box 0.1 x 0.2 x 0.3 m as six quads, in node "box" (translate 1 2 3) under node "group"
//   (translate 0 0 1):
//     it spans (1, 2, 4) .. (1.1, 2.2, 4.3)
//   tetrahedron with legs 0.3 m as triangles, in node "tet" (translate -1 0 0, then rotate 90 deg
//   about z):
//     its corners (0.3,0,0), (0,0.3,0), (0,0,0.3) go to (-1,0.3,0), (-1.3,0,0), (-1,0,0.3)
// so the whole spans (-1.3, 0, 0) .. (1.1, 2.2, 4.3) and holds 8 + 4 = 12 distinct corners and
// 6 * 2 + 4 = 16 triangles; volume 0.1 * 0.2 * 0.3 + 0.3^3 / 6 = 0.006 + 0.0045 = 0.0105 m^3.
// Without the tetrahedron: the box alone, 0.006 m^3. MuJoCo 2.2's mesh mass is exact for a box only
// (it overestimates a tetrahedron and fills the gap between disjoint parts), so its mass is checked
// on the box.
std::string collada(const std::string& up_axis, bool with_tet = true) {
  return R"(<?xml version="1.0" encoding="utf-8"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
  <asset><unit name="meter" meter="1"/><up_axis>)" +
         up_axis + R"(</up_axis></asset>
  <library_geometries>
    <geometry id="box" name="box"><mesh>
      <source id="box-pos">
        <float_array id="box-pos-array" count="24">
          0 0 0  0.1 0 0  0.1 0.2 0  0 0.2 0  0 0 0.3  0.1 0 0.3  0.1 0.2 0.3  0 0.2 0.3
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
    <geometry id="tet" name="tet"><mesh>
      <source id="tet-pos">
        <float_array id="tet-pos-array" count="12">0 0 0  0.3 0 0  0 0.3 0  0 0 0.3</float_array>
        <technique_common><accessor source="#tet-pos-array" count="4" stride="3">
          <param name="X" type="float"/><param name="Y" type="float"/><param name="Z" type="float"/>
        </accessor></technique_common>
      </source>
      <vertices id="tet-vtx"><input semantic="POSITION" source="#tet-pos"/></vertices>
      <triangles count="4">
        <input semantic="VERTEX" source="#tet-vtx" offset="0"/>
        <p>0 2 1  0 1 3  0 3 2  1 2 3</p>
      </triangles>
    </mesh></geometry>
  </library_geometries>
  <library_visual_scenes>
    <visual_scene id="scene" name="scene">
      <node id="group" name="group">
        <translate>0 0 1</translate>
        <node id="box-node" name="box"><translate>1 2 3</translate><instance_geometry url="#box"/></node>
      </node>
)" +
         (with_tet ? std::string(R"(
      <node id="tet-node" name="tet">
        <translate>-1 0 0</translate><rotate>0 0 1 90</rotate>
        <instance_geometry url="#tet"/>
      </node>
)")
                   : std::string()) +
         R"(
    </visual_scene>
  </library_visual_scenes>
  <scene><instance_visual_scene url="#scene"/></scene>
</COLLADA>
)";
}
constexpr int kCorners = 12;
constexpr int kTriangles = 16;
constexpr double kVolumeM3 = 0.0105;
constexpr double kBoxVolumeM3 = 0.006;
constexpr double kDensityKgM3 = 1000.0;  // MuJoCo's default geom density

struct ModelDeleter {
  void operator()(mjModel* m) const { mj_deleteModel(m); }
};
using ModelPtr = std::unique_ptr<mjModel, ModelDeleter>;

fs::path temp_dir() {
  fs::path dir = fs::path(::testing::TempDir()) / "mesh_convert_test";
  fs::create_directories(dir);
  return dir;
}

fs::path write_file(const std::string& name, const std::string& text) {
  const fs::path path = temp_dir() / name;
  std::ofstream(path) << text;
  return path;
}

// loads a one-body MJCF with the mesh file as a geom of default density
ModelPtr load_with_mesh(const fs::path& mesh_file) {
  const fs::path xml = write_file(mesh_file.stem().string() + "_model.xml", R"(
<mujoco>
  <asset><mesh name="converted" file=")" + mesh_file.string() + R"("/></asset>
  <worldbody><body name="part"><geom type="mesh" mesh="converted"/></body></worldbody>
</mujoco>)");
  char error[1000] = "";
  ModelPtr m(mj_loadXML(xml.string().c_str(), nullptr, error, sizeof(error)));
  EXPECT_NE(m, nullptr) << error;
  return m;
}

// the mesh's bounding box in the world: MuJoCo re-centres meshes at their centre of mass and moves
// the geom to compensate, so map its vertices through the geom's pose
void world_bounds(const mjModel* m, Eigen::Vector3d* lo, Eigen::Vector3d* hi) {
  mjData* d = mj_makeData(m);
  mj_forward(m, d);
  const Eigen::Map<const Eigen::Vector3d> pos(d->geom_xpos);
  const Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>> rot(d->geom_xmat);
  *lo = Eigen::Vector3d::Constant(1e9);
  *hi = Eigen::Vector3d::Constant(-1e9);
  const float* vert = m->mesh_vert + 3 * m->mesh_vertadr[0];
  for (int v = 0; v < m->mesh_vertnum[0]; ++v) {
    const Eigen::Vector3d p =
        rot * Eigen::Vector3d(vert[3 * v], vert[3 * v + 1], vert[3 * v + 2]) + pos;
    *lo = lo->cwiseMin(p);
    *hi = hi->cwiseMax(p);
  }
  mj_deleteData(d);
}

// MuJoCo 2.2 may store a vertex once per face that uses it
int distinct_vertices(const mjModel* m) {
  std::set<std::array<float, 3>> distinct;
  const float* vert = m->mesh_vert + 3 * m->mesh_vertadr[0];
  for (int v = 0; v < m->mesh_vertnum[0]; ++v) {
    distinct.insert({vert[3 * v], vert[3 * v + 1], vert[3 * v + 2]});
  }
  return static_cast<int>(distinct.size());
}

void expect_vec_near(const Eigen::Vector3d& actual, const Eigen::Vector3d& expected, double tol) {
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(actual[i], expected[i], tol) << "component " << i;
}

TEST(MeshConvert, ColladaNodesMergeWithTheirTransforms) {
  const TriangleMesh mesh = load_mesh(write_file("scene_zup.dae", collada("Z_UP")));
  EXPECT_EQ(mesh.source_meshes, 2);
  EXPECT_EQ(mesh.vertices_m.size(), static_cast<size_t>(kCorners));
  EXPECT_EQ(mesh.triangles.size(), static_cast<size_t>(kTriangles));  // quads split in two
  expect_vec_near(mesh.min_m(), {-1.3, 0, 0}, kCoordTol);
  expect_vec_near(mesh.max_m(), {1.1, 2.2, 4.3}, kCoordTol);
  EXPECT_NEAR(mesh.volume_m3(), kVolumeM3, kVolumeTol);  // positive: every face winds outward
}

TEST(MeshConvert, MergedMeshLoadsInMujocoInPlace) {
  const fs::path obj = temp_dir() / "scene.obj";
  convert_mesh(write_file("scene_zup.dae", collada("Z_UP")), obj);
  const ModelPtr m = load_with_mesh(obj);
  ASSERT_NE(m, nullptr);
  // MuJoCo 2.2 un-shares OBJ vertices (3 per face): count the distinct ones
  EXPECT_EQ(m->mesh_facenum[0], kTriangles);
  EXPECT_EQ(distinct_vertices(m.get()), kCorners);
  Eigen::Vector3d lo, hi;
  world_bounds(m.get(), &lo, &hi);
  expect_vec_near(lo, {-1.3, 0, 0}, kCoordTol);
  expect_vec_near(hi, {1.1, 2.2, 4.3}, kCoordTol);
}

TEST(MeshConvert, ObjAndStlGiveMujocoTheMassOfTheVolume) {
  const fs::path dae = write_file("box_zup.dae", collada("Z_UP", /*with_tet=*/false));
  for (const char* name : {"box.obj", "box.stl"}) {
    SCOPED_TRACE(name);
    const fs::path out = temp_dir() / name;
    const TriangleMesh mesh = convert_mesh(dae, out);
    EXPECT_NEAR(mesh.volume_m3(), kBoxVolumeM3, kVolumeTol);
    const ModelPtr m = load_with_mesh(out);
    ASSERT_NE(m, nullptr);
    EXPECT_EQ(m->mesh_facenum[0], 12);
    EXPECT_EQ(distinct_vertices(m.get()), 8);
    // mass = density * volume = 1000 * 0.006 = 6 kg: only if every face winds outward
    const double mass_kg = kDensityKgM3 * kBoxVolumeM3;
    EXPECT_NEAR(m->body_mass[1], mass_kg, kMassRelTol * mass_kg);
    Eigen::Vector3d lo, hi;
    world_bounds(m.get(), &lo, &hi);
    expect_vec_near(lo, {1, 2, 4}, kCoordTol);
    expect_vec_near(hi, {1.1, 2.2, 4.3}, kCoordTol);
  }
  // binary STL: 80-byte header + count + 50 bytes per triangle
  EXPECT_EQ(fs::file_size(temp_dir() / "box.stl"), 84u + 50u * 12u);
}

TEST(MeshConvert, ScaleAppliesToCoordinatesAndVolume) {
  MeshConvertOptions options;
  options.scale = 2.0;
  const fs::path obj = temp_dir() / "box_x2.obj";
  const TriangleMesh mesh =
      convert_mesh(write_file("box_zup.dae", collada("Z_UP", false)), obj, options);
  expect_vec_near(mesh.min_m(), {2, 4, 8}, kCoordTol);
  expect_vec_near(mesh.max_m(), {2.2, 4.4, 8.6}, kCoordTol);
  // twice the size, eight times the mass: 48 kg
  const ModelPtr m = load_with_mesh(obj);
  ASSERT_NE(m, nullptr);
  const double mass_kg = 8.0 * kDensityKgM3 * kBoxVolumeM3;
  EXPECT_NEAR(m->body_mass[1], mass_kg, kMassRelTol * mass_kg);
}

TEST(MeshConvert, YUpColladaIsTurnedZUp) {
  // the file's +y is up: (x, y, z) -> (x, -z, y)
  const TriangleMesh mesh = load_mesh(write_file("scene_yup.dae", collada("Y_UP")));
  expect_vec_near(mesh.min_m(), {-1.3, -4.3, 0}, kCoordTol);
  expect_vec_near(mesh.max_m(), {1.1, 0, 2.2}, kCoordTol);
  // and kept as assimp gives it (y-up) when asked
  MeshConvertOptions keep;
  keep.z_up = false;
  const TriangleMesh raw = load_mesh(write_file("scene_yup.dae", collada("Y_UP")), keep);
  expect_vec_near(raw.max_m(), {1.1, 2.2, 4.3}, kCoordTol);
}

TEST(MeshConvert, PlyWithoutUpAxisKeepsItsCoordinates) {
  // ASCII PLY tetrahedron: no up axis, so nothing turns
  const fs::path ply = write_file("tet.ply", R"(ply
format ascii 1.0
element vertex 4
property float x
property float y
property float z
element face 4
property list uchar int vertex_indices
end_header
0 0 0
0.3 0 0
0 0.3 0
0 0 0.3
3 0 2 1
3 0 1 3
3 0 3 2
3 1 2 3
)");
  const fs::path obj = temp_dir() / "tet.obj";
  const TriangleMesh mesh = convert_mesh(ply, obj);
  EXPECT_EQ(mesh.vertices_m.size(), 4u);
  expect_vec_near(mesh.max_m(), {0.3, 0.3, 0.3}, kCoordTol);
  EXPECT_NEAR(mesh.volume_m3(), 0.0045, kVolumeTol);  // 0.3^3 / 6
  const ModelPtr m = load_with_mesh(obj);
  ASSERT_NE(m, nullptr);
  EXPECT_EQ(m->mesh_facenum[0], 4);
}

TEST(MeshConvert, MissingFileFailsNamingIt) {
  const fs::path missing = temp_dir() / "no_such_mesh.dae";
  try {
    load_mesh(missing);
    FAIL() << "expected std::runtime_error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(missing.string()), std::string::npos) << e.what();
  }
}

TEST(MeshConvert, UnreadableFileFailsNamingIt) {
  const fs::path junk = write_file("junk.dae", "this is not COLLADA\n");
  try {
    load_mesh(junk);
    FAIL() << "expected std::runtime_error";
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(junk.string()), std::string::npos) << what;
  }
}

TEST(MeshConvert, BadOptionsFail) {
  const fs::path dae = write_file("scene_zup.dae", collada("Z_UP"));
  MeshConvertOptions flat;
  flat.scale = 0.0;
  EXPECT_THROW(load_mesh(dae, flat), std::invalid_argument);
  EXPECT_THROW(convert_mesh(dae, temp_dir() / "scene.msh"), std::invalid_argument);
}

}  // namespace
}  // namespace uavsim::server::assets
