// Mesh conversion for worlds: MuJoCo 2.2 reads only STL, OBJ and MSH meshes, so meshes in the
// formats Gazebo models and artists use (COLLADA .dae, glTF, FBX, PLY, 3DS, ... anything assimp
// reads) are converted once, at world-composition time, into one OBJ or binary STL file MuJoCo can
// load.
#pragma once

#include <Eigen/Core>
#include <filesystem>
#include <optional>
#include <vector>

namespace uavsim::server::assets {

enum class MeshFormat {
  kObj,        // Wavefront OBJ: positions and triangles only, vertices shared
  kStlBinary,  // binary STL (MuJoCo 2.2 does not read ASCII STL)
};

struct MeshConvertOptions {
  // uniform scale applied to the output, after the file's own unit (COLLADA <unit meter>) is
  // applied
  double scale = 1.0;
  // bring the result to MuJoCo's z-up: files that declare an up axis (COLLADA <up_axis>, FBX's
  // UpAxis, glTF which is y-up by definition) are rotated so that it becomes +z; files that declare
  // none (OBJ, STL, PLY, ...) keep their coordinates. false: keep assimp's y-up for the former.
  bool z_up = true;
  // output format; unset: from the output file's extension (.obj or .stl)
  std::optional<MeshFormat> format;
};

// All triangles of a file in one mesh, node transforms applied, identical positions merged.
struct TriangleMesh {
  std::vector<Eigen::Vector3d> vertices_m;
  std::vector<Eigen::Vector3i>
      triangles;          // indices into vertices_m, counter-clockwise seen from outside
  int source_meshes = 0;  // mesh instances merged (a mesh used by two nodes counts twice)

  Eigen::Vector3d min_m() const;  // axis-aligned bounding box; zero for an empty mesh
  Eigen::Vector3d max_m() const;
  // Enclosed volume by the divergence theorem (sum of signed tetrahedra); exact for closed,
  // outward-wound meshes, negative when wound inside out. MuJoCo 2.2's own mesh volume is exact for
  // boxes but not in general (it overestimates a tetrahedron by 39% and fills the space between
  // disjoint parts).
  double volume_m3() const;
};

// Reads every mesh of `input` that assimp understands, places each instance with its node's
// transform, triangulates polygons, drops points and lines, merges identical positions and applies
// `options`. Throws std::runtime_error naming the file if it is missing, unreadable, or holds no
// triangles; std::invalid_argument for a non-positive scale.
TriangleMesh load_mesh(const std::filesystem::path& input, const MeshConvertOptions& options = {});

// Writes `mesh` as `format`. Throws std::runtime_error naming the file if it cannot be written.
void write_mesh(const TriangleMesh& mesh, const std::filesystem::path& output, MeshFormat format);

// load_mesh(input) then write_mesh(output): the one call a world composer needs. Returns the mesh
// written. Throws as those two do, and std::invalid_argument if the format is unset and the output
// extension is neither .obj nor .stl.
TriangleMesh convert_mesh(const std::filesystem::path& input, const std::filesystem::path& output,
                          const MeshConvertOptions& options = {});

}  // namespace uavsim::server::assets
