#include "assets/mesh_convert.hpp"

#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <algorithm>
#include <array>
#include <assimp/Importer.hpp>
#include <cctype>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <map>
#include <stdexcept>
#include <string>

namespace uavsim::server::assets {

namespace {

using Matrix4 = Eigen::Matrix4d;

Matrix4 to_eigen(const aiMatrix4x4& a) {
  Matrix4 m;
  m << a.a1, a.a2, a.a3, a.a4, a.b1, a.b2, a.b3, a.b4, a.c1, a.c2, a.c3, a.c4, a.d1, a.d2, a.d3,
      a.d4;
  return m;
}

std::string lower_extension(const std::filesystem::path& p) {
  std::string ext = p.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  return ext;
}

// rotation that takes the file's declared up axis to +z; identity if it declares none
Eigen::Matrix3d up_to_z(const aiScene& scene, const std::filesystem::path& input) {
  // y-up to z-up: +90 degrees about x, (x, y, z) -> (x, -z, y)
  Eigen::Matrix3d y_to_z;
  y_to_z << 1, 0, 0, 0, 0, -1, 0, 1, 0;

  // FBX (and any importer that fills it) states its up axis in the scene metadata: 0 x, 1 y, 2 z
  int up_axis = -1;
  int up_sign = 1;
  if (scene.mMetaData != nullptr && scene.mMetaData->Get("UpAxis", up_axis)) {
    scene.mMetaData->Get("UpAxisSign", up_sign);
    Eigen::Matrix3d r = Eigen::Matrix3d::Identity();
    if (up_axis == 0) r << 0, 0, -1, 0, 1, 0, 1, 0, 0;  // -90 degrees about y: x -> z
    if (up_axis == 1) r = y_to_z;
    // a negative up axis: a half turn about the horizontal x axis
    if (up_sign < 0) r = Eigen::Vector3d(1, -1, -1).asDiagonal() * r;
    return r;
  }
  // assimp brings COLLADA to y-up whatever its <up_axis>; glTF is y-up by definition
  const std::string ext = lower_extension(input);
  if (ext == ".dae" || ext == ".gltf" || ext == ".glb") return y_to_z;
  return Eigen::Matrix3d::Identity();
}

// merges positions exactly equal after transformation
struct VertexPool {
  std::map<std::array<double, 3>, int> index;
  std::vector<Eigen::Vector3d>* vertices;

  int add(const Eigen::Vector3d& p) {
    const auto [it, inserted] =
        index.try_emplace({p.x(), p.y(), p.z()}, static_cast<int>(vertices->size()));
    if (inserted) vertices->push_back(p);
    return it->second;
  }
};

// walk the node tree, placing each mesh instance with the product of the transforms above it
void collect(const aiScene& scene, const aiNode& node, const Matrix4& parent_to_out,
             VertexPool* pool, TriangleMesh* out) {
  const Matrix4 node_to_out = parent_to_out * to_eigen(node.mTransformation);
  const Eigen::Matrix3d linear = node_to_out.topLeftCorner<3, 3>();
  // a mirroring transform turns counter-clockwise faces clockwise: swap two corners back
  const bool mirrored = linear.determinant() < 0.0;
  for (unsigned k = 0; k < node.mNumMeshes; ++k) {
    const aiMesh& mesh = *scene.mMeshes[node.mMeshes[k]];
    std::vector<int> remap(mesh.mNumVertices);
    for (unsigned v = 0; v < mesh.mNumVertices; ++v) {
      const aiVector3D& a = mesh.mVertices[v];
      remap[v] =
          pool->add(linear * Eigen::Vector3d(a.x, a.y, a.z) + node_to_out.topRightCorner<3, 1>());
    }
    for (unsigned f = 0; f < mesh.mNumFaces; ++f) {
      const aiFace& face = mesh.mFaces[f];
      if (face.mNumIndices != 3) continue;  // points and lines
      Eigen::Vector3i t(remap[face.mIndices[0]], remap[face.mIndices[1]], remap[face.mIndices[2]]);
      if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) continue;  // collapsed by merging
      if (mirrored) std::swap(t[1], t[2]);
      out->triangles.push_back(t);
    }
    ++out->source_meshes;
  }
  for (unsigned c = 0; c < node.mNumChildren; ++c) {
    collect(scene, *node.mChildren[c], node_to_out, pool, out);
  }
}

void write_obj(const TriangleMesh& mesh, std::ofstream& file) {
  char line[128];
  file << "# converted by uavsim mesh_convert\n";
  for (const Eigen::Vector3d& v : mesh.vertices_m) {
    std::snprintf(line, sizeof(line), "v %.9g %.9g %.9g\n", v.x(), v.y(), v.z());
    file << line;
  }
  // OBJ indices are 1-based
  for (const Eigen::Vector3i& t : mesh.triangles) {
    file << "f " << t[0] + 1 << ' ' << t[1] + 1 << ' ' << t[2] + 1 << '\n';
  }
}

template <typename T>
void put(std::ofstream& file, T value) {
  file.write(reinterpret_cast<const char*>(&value), sizeof(value));  // little-endian hosts only
}

void write_stl(const TriangleMesh& mesh, std::ofstream& file) {
  // 80-byte header (must not start with "solid", which marks ASCII STL), triangle count, then per
  // triangle: normal, three corners (float32 each) and a 16-bit attribute
  char header[80] = "binary STL converted by uavsim mesh_convert";
  file.write(header, sizeof(header));
  put<uint32_t>(file, static_cast<uint32_t>(mesh.triangles.size()));
  for (const Eigen::Vector3i& t : mesh.triangles) {
    const Eigen::Vector3d& a = mesh.vertices_m[t[0]];
    const Eigen::Vector3d& b = mesh.vertices_m[t[1]];
    const Eigen::Vector3d& c = mesh.vertices_m[t[2]];
    const Eigen::Vector3d n = (b - a).cross(c - a).normalized();
    for (const Eigen::Vector3d* p : {&n, &a, &b, &c}) {
      for (int i = 0; i < 3; ++i) put<float>(file, static_cast<float>((*p)[i]));
    }
    put<uint16_t>(file, 0);
  }
}

}  // namespace

Eigen::Vector3d TriangleMesh::min_m() const {
  if (vertices_m.empty()) return Eigen::Vector3d::Zero();
  Eigen::Vector3d lo = vertices_m.front();
  for (const Eigen::Vector3d& v : vertices_m) lo = lo.cwiseMin(v);
  return lo;
}

Eigen::Vector3d TriangleMesh::max_m() const {
  if (vertices_m.empty()) return Eigen::Vector3d::Zero();
  Eigen::Vector3d hi = vertices_m.front();
  for (const Eigen::Vector3d& v : vertices_m) hi = hi.cwiseMax(v);
  return hi;
}

double TriangleMesh::volume_m3() const {
  // each triangle and the origin span a tetrahedron of signed volume a . (b x c) / 6
  double volume = 0.0;
  for (const Eigen::Vector3i& t : triangles) {
    volume += vertices_m[t[0]].dot(vertices_m[t[1]].cross(vertices_m[t[2]])) / 6.0;
  }
  return volume;
}

TriangleMesh load_mesh(const std::filesystem::path& input, const MeshConvertOptions& options) {
  if (!(options.scale > 0.0)) {
    throw std::invalid_argument("mesh_convert: scale must be positive, got " +
                                std::to_string(options.scale) + " for '" + input.string() + "'");
  }
  if (!std::filesystem::is_regular_file(input)) {
    throw std::runtime_error("mesh_convert: no such file '" + input.string() + "'");
  }

  // import with polygons triangulated; node transforms are applied below, so instances stay correct
  Assimp::Importer importer;
  const aiScene* scene = importer.ReadFile(input.string(), aiProcess_Triangulate);
  if (scene == nullptr || scene->mRootNode == nullptr) {
    throw std::runtime_error("mesh_convert: cannot read '" + input.string() +
                             "': " + importer.GetErrorString());
  }

  // output = scale * up_to_z * (node transforms) * mesh vertices
  Matrix4 root = Matrix4::Identity();
  root.topLeftCorner<3, 3>() =
      options.scale * (options.z_up ? up_to_z(*scene, input) : Eigen::Matrix3d::Identity());
  TriangleMesh mesh;
  VertexPool pool{{}, &mesh.vertices_m};
  collect(*scene, *scene->mRootNode, root, &pool, &mesh);

  if (mesh.triangles.empty()) {
    throw std::runtime_error("mesh_convert: '" + input.string() + "' holds no triangles (" +
                             std::to_string(scene->mNumMeshes) + " meshes)");
  }
  return mesh;
}

void write_mesh(const TriangleMesh& mesh, const std::filesystem::path& output, MeshFormat format) {
  std::ofstream file(output, std::ios::binary | std::ios::trunc);
  if (!file)
    throw std::runtime_error("mesh_convert: cannot open '" + output.string() + "' for writing");
  if (format == MeshFormat::kObj) {
    write_obj(mesh, file);
  } else {
    write_stl(mesh, file);
  }
  file.close();
  if (!file) throw std::runtime_error("mesh_convert: error writing '" + output.string() + "'");
}

TriangleMesh convert_mesh(const std::filesystem::path& input, const std::filesystem::path& output,
                          const MeshConvertOptions& options) {
  // the format: given, or from the output extension
  MeshFormat format = MeshFormat::kObj;
  if (options.format) {
    format = *options.format;
  } else if (lower_extension(output) == ".obj") {
    format = MeshFormat::kObj;
  } else if (lower_extension(output) == ".stl") {
    format = MeshFormat::kStlBinary;
  } else {
    throw std::invalid_argument("mesh_convert: cannot tell the format of '" + output.string() +
                                "': use a .obj or .stl extension or set options.format");
  }
  TriangleMesh mesh = load_mesh(input, options);
  write_mesh(mesh, output, format);
  return mesh;
}

}  // namespace uavsim::server::assets
