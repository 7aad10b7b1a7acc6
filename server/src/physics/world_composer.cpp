#include "physics/world_composer.hpp"

#include <tinyxml2.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <map>
#include <memory>
#include <set>
#include <sstream>
#include <string_view>
#include <thread>
#include <vector>

#include "assets/mesh_convert.hpp"
#include "uavsim/common/install_paths.hpp"
#include "uavsim/common/mavlink/sha256.hpp"
#include "uavsim/common/angles.hpp"

namespace uavsim::server::physics {

namespace fs = std::filesystem;
using tinyxml2::XMLDocument;
using tinyxml2::XMLElement;
using tinyxml2::XMLNode;

namespace {

using common::kPi;

// bounds on what a world file may ask for; each error says which and why
constexpr double kMaxCoordinate_m = 1e5;  // MuJoCo resets (t = 0, forever) on positions past 1e10
constexpr double kMaxYaw_deg = 360.0;
constexpr double kMaxSpacing_m = 1e4;
// MuJoCo 2.2 sizes its constraint buffers densely (njmax x (nv + njmax)), so the rows left for contacts
// shrink as vehicles are added (auto_njmax); 3000 is the most the benchmarks run
constexpr long kMaxVehicles = 3000;
// includes: total files and bytes over the whole world, so that a fan-out (each file including the
// next several times) fails at once instead of growing exponentially
constexpr int kMaxIncludedFiles = 256;
constexpr std::uintmax_t kMaxIncludedBytes = 64u << 20;
constexpr size_t kMaxCollisionWords = 32;  // collision="...": geom-name prefixes
// physics shards "auto": worlds of this many vehicles or more get one shard per hardware thread, up to
// kMaxAutoShards (a shard's fixed cost, its lockstep hand-off, only pays off for a few hundred vehicles)
constexpr long kAutoShardMinVehicles = 200;
constexpr int kMaxAutoShards = 8;

[[noreturn]] void fail(const std::string& file, int line, const std::string& what) {
  std::ostringstream s;
  s << file << ":" << line << ": " << what;
  throw WorldError(s.str());
}

// Strict attribute parsing: a present attribute must be entirely a finite number in range ("nan",
// "1e300", "3x" and "" are errors naming the file and line); an absent one takes the fallback.
double number_attr(const XMLElement* e, const char* attr, double fallback, double lo, double hi,
                   const std::string& file) {
  const char* text = e->Attribute(attr);
  if (text == nullptr) return fallback;
  char* end = nullptr;
  const double v = std::strtod(text, &end);
  while (end != nullptr && std::isspace(static_cast<unsigned char>(*end))) ++end;
  if (end == text || *end != '\0' || !std::isfinite(v) || v < lo || v > hi) {
    std::ostringstream s;
    s << attr << "=\"" << text << "\" must be a number in [" << lo << ", " << hi << "]";
    fail(file, e->GetLineNum(), s.str());
  }
  return v;
}

long integer_attr(const XMLElement* e, const char* attr, long fallback, long lo, long hi,
                  const std::string& file) {
  const double v = number_attr(e, attr, static_cast<double>(fallback), static_cast<double>(lo),
                               static_cast<double>(hi), file);
  if (v != std::trunc(v)) fail(file, e->GetLineNum(), std::string(attr) + " must be a whole number");
  return static_cast<long>(v);
}

// "x y z": exactly three finite numbers of at most kMaxCoordinate_m; absent: zeros
void vec3_attr(const XMLElement* e, const char* attr, double out[3], const std::string& file) {
  out[0] = out[1] = out[2] = 0.0;
  const char* text = e->Attribute(attr);
  if (text == nullptr) return;
  const char* p = text;
  for (int i = 0; i < 3; ++i) {
    char* end = nullptr;
    out[i] = std::strtod(p, &end);
    if (end == p || !std::isfinite(out[i]) || std::abs(out[i]) > kMaxCoordinate_m) {
      std::ostringstream s;
      s << attr << "=\"" << text << "\" must be three numbers of at most " << kMaxCoordinate_m << " m";
      fail(file, e->GetLineNum(), s.str());
    }
    p = end;
  }
  while (std::isspace(static_cast<unsigned char>(*p))) ++p;
  if (*p != '\0') fail(file, e->GetLineNum(), std::string(attr) + "=\"" + text + "\" has more than three numbers");
}

// the composition's running total of included files and bytes
struct IncludeBudget {
  int files = 0;
  std::uintmax_t bytes = 0;
};

std::unique_ptr<XMLDocument> load_xml(const std::string& path) {
  auto doc = std::make_unique<XMLDocument>();
  if (!fs::exists(path)) fail(path, 0, "file not found");
  if (doc->LoadFile(path.c_str()) != tinyxml2::XML_SUCCESS) {
    fail(path, doc->ErrorLineNum(), std::string("malformed XML: ") + doc->ErrorStr());
  }
  XMLElement* root = doc->RootElement();
  if (root == nullptr || std::string(root->Name()) != "mujoco") {
    fail(path, root ? root->GetLineNum() : 1, "the root element must be <mujoco>");
  }
  return doc;
}

XMLElement* child_or_create(XMLDocument& doc, XMLElement* parent, const char* name,
                            bool at_front = false) {
  XMLElement* e = parent->FirstChildElement(name);
  if (e != nullptr) return e;
  e = doc.NewElement(name);
  if (at_front) {
    parent->InsertFirstChild(e);
  } else {
    parent->InsertEndChild(e);
  }
  return e;
}

std::string compiler_attr(XMLElement* root, const char* attr, const char* fallback) {
  for (XMLElement* c = root->FirstChildElement("compiler"); c; c = c->NextSiblingElement("compiler")) {
    if (const char* v = c->Attribute(attr)) return v;
  }
  return fallback;
}

// make every asset file path absolute: meshes and height fields resolve against meshdir, textures
// against texturedir, both relative to the file that declares them (MuJoCo's rules)
void absolutize_asset_paths(XMLElement* root, const fs::path& base_dir, const std::string& xml_file) {
  const fs::path mesh_dir = base_dir / compiler_attr(root, "meshdir", "");
  const fs::path texture_dir = base_dir / compiler_attr(root, "texturedir", "");
  for (XMLElement* asset = root->FirstChildElement("asset"); asset;
       asset = asset->NextSiblingElement("asset")) {
    for (XMLElement* e = asset->FirstChildElement(); e; e = e->NextSiblingElement()) {
      const char* file = e->Attribute("file");
      if (file == nullptr || fs::path(file).is_absolute()) continue;
      const std::string kind = e->Name();
      const fs::path dir = (kind == "texture") ? texture_dir : mesh_dir;
      std::error_code ec;
      const fs::path absolute = fs::weakly_canonical(dir / file, ec);
      if (ec) fail(xml_file, e->GetLineNum(), "asset file '" + std::string(file) + "': " + ec.message());
      e->SetAttribute("file", absolute.string().c_str());
    }
  }
  for (XMLElement* c = root->FirstChildElement("compiler"); c; c = c->NextSiblingElement("compiler")) {
    c->DeleteAttribute("meshdir");
    c->DeleteAttribute("texturedir");
  }
}

// The file an <include file="inc"/> names: beside the including file, else (a relative name) in the
// shipped models as if the including file were a shipped world, so that a world of one's own
// anywhere includes the shipped parts as the shipped worlds do (file="../common/ground.xml") or by
// their place in the models (file="common/ground.xml"). Fails naming every place it looked.
fs::path find_include(const std::string& inc, const fs::path& base_dir, const fs::path& models_dir,
                      const std::string& file, int line) {
  std::vector<fs::path> candidates{base_dir / inc};
  if (fs::path(inc).is_relative() && !models_dir.empty()) {
    candidates.push_back((models_dir / "worlds" / inc).lexically_normal());
    candidates.push_back((models_dir / inc).lexically_normal());
  }
  std::string looked;
  for (const fs::path& c : candidates) {
    std::error_code ec;
    const bool exists = fs::exists(c, ec);
    if (ec) fail(file, line, "included file '" + inc + "': " + ec.message());
    if (exists) return c;
    looked += (looked.empty() ? "" : ", ") + c.string();
  }
  fail(file, line, "included file not found: " + inc + " (looked for " + looked + ")");
}

// replace each <include file=.../> with the children of the included file's <mujoco>, recursively
void inline_includes(XMLDocument& doc, XMLElement* element, const fs::path& base_dir,
                     const fs::path& models_dir, const std::string& file, int depth,
                     IncludeBudget* budget) {
  if (depth > 16) fail(file, element->GetLineNum(), "includes nested more than 16 deep");
  for (XMLElement* e = element->FirstChildElement(); e;) {
    XMLElement* next = e->NextSiblingElement();
    if (std::string(e->Name()) != "include") {
      inline_includes(doc, e, base_dir, models_dir, file, depth, budget);
      e = next;
      continue;
    }
    const char* inc = e->Attribute("file");
    if (inc == nullptr) fail(file, e->GetLineNum(), "<include> without file=");
    const fs::path inc_path = find_include(inc, base_dir, models_dir, file, e->GetLineNum());
    std::error_code ec;
    // every include counts, however often the same file comes back
    budget->bytes += fs::file_size(inc_path, ec);
    if (++budget->files > kMaxIncludedFiles || budget->bytes > kMaxIncludedBytes) {
      fail(file, e->GetLineNum(),
           "the world includes more than " + std::to_string(kMaxIncludedFiles) + " files or " +
               std::to_string(kMaxIncludedBytes >> 20) + " MiB in all (counting repeats): is a file included "
               "over and over?");
    }
    auto inc_doc = load_xml(inc_path.string());
    XMLElement* inc_root = inc_doc->RootElement();
    absolutize_asset_paths(inc_root, inc_path.parent_path(), inc_path.string());
    inline_includes(*inc_doc, inc_root, inc_path.parent_path(), models_dir, inc_path.string(),
                    depth + 1, budget);
    // copy the included children in place of the <include>, keeping their order
    XMLNode* anchor = e->PreviousSibling();
    for (XMLNode* n = inc_root->FirstChild(); n; n = n->NextSibling()) {
      XMLNode* copy = n->DeepClone(&doc);
      anchor = anchor ? element->InsertAfterChild(anchor, copy) : element->InsertFirstChild(copy);
    }
    element->DeleteChild(e);
    e = next;
  }
}

// --- meshes MuJoCo 2.2 cannot read ---

// bump when the conversion's output changes, so that stale cache entries are not reused
constexpr const char* kMeshCacheVersion = "uavsim-mesh-obj-1";

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
  return s;
}

// MuJoCo 2.2 reads OBJ, MSH and binary STL (not ASCII STL); a binary STL is 84 + 50 n bytes
bool mujoco_reads(const fs::path& file) {
  const std::string ext = lower(file.extension().string());
  if (ext == ".obj" || ext == ".msh") return true;
  if (ext != ".stl") return false;
  std::ifstream in(file, std::ios::binary);
  char header[84] = {};
  if (!in.read(header, sizeof(header))) return true;  // too short for either: let MuJoCo report it
  const std::uint32_t n = static_cast<std::uint8_t>(header[80]) | static_cast<std::uint8_t>(header[81]) << 8 |
                          static_cast<std::uint8_t>(header[82]) << 16 |
                          static_cast<std::uint32_t>(static_cast<std::uint8_t>(header[83])) << 24;
  std::error_code ec;
  const auto size = fs::file_size(file, ec);
  return ec || size == 84 + 50 * static_cast<std::uintmax_t>(n) || std::string(header, 5) != "solid";
}

// SHA-256 of the cache version and the file's bytes, in hex: the cache file's name. A cryptographic hash,
// so no other content can be made to hit an entry (the project's one SHA-256, from MAVLink signing).
std::string content_hash(const fs::path& file) {
  common::mavlink::Sha256 h;
  const std::string_view version = kMeshCacheVersion;
  h.update({reinterpret_cast<const std::uint8_t*>(version.data()), version.size()});
  std::ifstream in(file, std::ios::binary);
  char buf[1 << 16];
  while (in.read(buf, sizeof(buf)) || in.gcount() > 0) {
    h.update({reinterpret_cast<const std::uint8_t*>(buf), static_cast<std::size_t>(in.gcount())});
  }
  std::ostringstream s;
  for (std::uint8_t b : h.finish()) s << std::hex << std::setw(2) << std::setfill('0') << static_cast<int>(b);
  return s.str();
}

// per user, never a directory others can write: $XDG_CACHE_HOME/uavsim/meshes, else
// ~/.cache/uavsim/meshes, else (no home) a directory in /tmp named after the user id
fs::path mesh_cache_dir(const ComposeOptions& options) {
  if (!options.mesh_cache_dir.empty()) return options.mesh_cache_dir;
  if (const char* xdg = std::getenv("XDG_CACHE_HOME"); xdg != nullptr && *xdg == '/') {
    return fs::path(xdg) / "uavsim" / "meshes";
  }
  if (const char* home = std::getenv("HOME"); home != nullptr && *home == '/') {
    return fs::path(home) / ".cache" / "uavsim" / "meshes";
  }
  return fs::temp_directory_path() / ("uavsim-mesh-cache-" + std::to_string(getuid()));
}

// the composed world no longer knows which file declared a mesh: name the world and the mesh
[[noreturn]] void mesh_fail(const std::string& world_path, const std::string& what) {
  throw WorldError(world_path + ": " + what);
}

// converts every <mesh file=...> MuJoCo 2.2 cannot read into the cache (once per content) and points the
// element at the OBJ; runs after the paths are absolute and every template's assets are merged
void convert_meshes(XMLElement* root, const std::string& world_path, const ComposeOptions& options) {
  for (XMLElement* asset = root->FirstChildElement("asset"); asset; asset = asset->NextSiblingElement("asset")) {
    for (XMLElement* mesh = asset->FirstChildElement("mesh"); mesh; mesh = mesh->NextSiblingElement("mesh")) {
      const char* file_attr = mesh->Attribute("file");
      if (file_attr == nullptr) continue;
      const fs::path source = file_attr;
      const std::string what = "mesh " + (mesh->Attribute("name") ? std::string("'") + mesh->Attribute("name") + "' "
                                                                  : std::string()) + "(" + source.string() + ")";
      std::error_code exists_ec;
      const bool exists = fs::exists(source, exists_ec);
      if (exists_ec) mesh_fail(world_path, what + ": " + exists_ec.message());
      if (!exists) mesh_fail(world_path, what + ": file not found");
      // MuJoCo reads a directory as an empty mesh ("no vertices"): say what it is
      if (fs::is_directory(source, exists_ec)) mesh_fail(world_path, what + ": is a directory, not a mesh file");
      if (mujoco_reads(source)) continue;

      const fs::path dir = mesh_cache_dir(options);
      const fs::path cached = dir / (source.stem().string() + "-" + content_hash(source) + ".obj");
      std::error_code cached_ec;
      if (!fs::exists(cached, cached_ec)) {
        std::error_code ec;
        fs::create_directories(dir, ec);
        if (ec) mesh_fail(world_path, what + ": cannot create the mesh cache " + dir.string() + ": " + ec.message());
        fs::permissions(dir, fs::perms::owner_all, fs::perm_options::replace, ec);  // private to its user
        // write under a private name, then rename: concurrent servers never see half a file
        const fs::path partial = dir / (cached.filename().string() + ".part" + std::to_string(getpid()));
        try {
          assets::MeshConvertOptions convert;
          convert.format = assets::MeshFormat::kObj;  // the private name has no .obj extension
          assets::convert_mesh(source, partial, convert);
        } catch (const std::exception& e) {
          fs::remove(partial, ec);
          mesh_fail(world_path, what + ": MuJoCo 2.2 reads only OBJ, MSH and binary STL, and converting it failed: " +
                                  e.what());
        }
        fs::rename(partial, cached, ec);
        if (ec) mesh_fail(world_path, what + ": cannot write the mesh cache " + cached.string() + ": " + ec.message());
      }
      // MuJoCo names an unnamed mesh after its file: keep the source's name for the geoms that use it
      if (mesh->Attribute("name") == nullptr) mesh->SetAttribute("name", source.stem().string().c_str());
      mesh->SetAttribute("file", cached.string().c_str());
    }
  }
}

std::string join3(const double v[3]) {
  std::ostringstream s;
  s.precision(10);
  s << v[0] << " " << v[1] << " " << v[2];
  return s.str();
}

// a vehicle or object template: its root body and the global parts it brings
struct Template {
  std::string path;
  std::unique_ptr<XMLDocument> doc;
  XMLElement* body = nullptr;  // the first <body> of <worldbody>
  std::string name;            // the root body's name, replaced by the instance name
  std::string angle;           // compiler angle unit
  int nuser_site = 0;
  bool globals_merged = false;  // defaults and assets are copied once per type
};

class Composer {
 public:
  Composer(std::string world_path, ComposeOptions options)
      : world_path_(std::move(world_path)), options_(std::move(options)) {}

  std::string compose() { return compose_shards(1).front(); }

  // The world split into physics shards (world_composer.hpp); shards 0: auto.
  std::vector<std::string> compose_shards(int shards) {
    world_ = load_xml(world_path_);
    XMLElement* root = world_->RootElement();
    const fs::path base = fs::absolute(world_path_).parent_path();
    absolutize_asset_paths(root, base, world_path_);
    IncludeBudget budget;
    inline_includes(*world_, root, base, options_.models_dir, world_path_, 0, &budget);
    world_angle_ = compiler_attr(root, "angle", "degree");
    // includes may leave several <worldbody> sections, as MuJoCo allows
    if (root->FirstChildElement("worldbody") == nullptr) fail(world_path_, root->GetLineNum(), "no <worldbody>");
    for (XMLElement* wb = root->FirstChildElement("worldbody"); wb; wb = wb->NextSiblingElement("worldbody")) {
      expand(wb);
    }
    check_nested(root);
    const std::string why_not = unshardable(root);
    if (shards == 0) {
      shards = (why_not.empty() && vehicles_ >= kAutoShardMinVehicles) ? auto_shard_count() : 1;
    }
    if (shards < 1 || shards > kMaxPhysicsShards) {
      throw WorldError(world_path_ + ": " + std::to_string(shards) + " physics shards: must be 1 to " +
                       std::to_string(kMaxPhysicsShards) + " (or auto)");
    }
    if (shards == 1) {
      finish(*world_, static_cast<long>(names_.size()));
      convert_meshes(root, world_path_, options_);
      if (!options_.vehicle_visual_geoms) strip_visual_geoms(root);
      return {print(*world_)};
    }
    if (!why_not.empty()) {
      throw WorldError(world_path_ + ": cannot be split into " + std::to_string(shards) + " physics shards: " +
                       why_not + " (shards hold vehicles and a static scene only; use 1 shard)");
    }
    if (vehicles_ < shards) {
      throw WorldError(world_path_ + ": " + std::to_string(shards) + " physics shards for " +
                       std::to_string(vehicles_) + " vehicle(s): each shard needs at least one vehicle");
    }
    convert_meshes(root, world_path_, options_);
    strip_visual_geoms(root);
    // contiguous blocks in world order, so that the concatenation of the shards' vehicles is the world's
    std::vector<std::string> out;
    const long objects = static_cast<long>(names_.size()) - vehicles_;
    for (int k = 0; k < shards; ++k) {
      const long first = vehicles_ * k / shards, end = vehicles_ * (k + 1) / shards;
      std::set<std::string> others;
      for (long i = 0; i < vehicles_; ++i) {
        if (i < first || i >= end) others.insert(vehicle_names_[static_cast<size_t>(i)]);
      }
      XMLDocument shard;
      world_->DeepCopy(&shard);
      remove_vehicles(shard.RootElement(), others);
      finish(shard, end - first + objects, shards);
      out.push_back(print(shard));
    }
    return out;
  }

 private:
  // expand the uavsim_* elements that are direct children of <worldbody>
  void expand(XMLElement* worldbody) {
    for (XMLElement* e = worldbody->FirstChildElement(); e;) {
      XMLElement* next = e->NextSiblingElement();
      const std::string tag = e->Name();
      if (tag == "uavsim_vehicle") {
        check_vehicle_count(e, 1);
        instantiate(worldbody, e, "vehicles", required(e, "name"), offset(e), yaw(e));
        worldbody->DeleteChild(e);
      } else if (tag == "uavsim_object") {
        instantiate(worldbody, e, "objects", required(e, "name"), offset(e), yaw(e));
        worldbody->DeleteChild(e);
      } else if (tag == "uavsim_grid") {
        expand_grid(worldbody, e);
        worldbody->DeleteChild(e);
      }
      e = next;
    }
  }

  void expand_grid(XMLElement* worldbody, XMLElement* e) {
    // each factor is bounded before the product, so rows * cols cannot overflow
    const long rows = integer_attr(e, "rows", 1, 1, kMaxVehicles, world_path_);
    const long cols = integer_attr(e, "cols", 1, 1, kMaxVehicles, world_path_);
    const double spacing = number_attr(e, "spacing", 3.0, 1e-3, kMaxSpacing_m, world_path_);
    check_vehicle_count(e, rows * cols);
    const std::string prefix = e->Attribute("prefix") ? e->Attribute("prefix") : "uav";
    double origin[3];
    vec3_attr(e, "pos", origin, world_path_);
    // the far corner must be in range too
    if (std::abs(origin[0]) + static_cast<double>(cols - 1) * spacing > kMaxCoordinate_m ||
        std::abs(origin[1]) + static_cast<double>(rows - 1) * spacing > kMaxCoordinate_m) {
      fail(world_path_, e->GetLineNum(), "the grid reaches past " + std::to_string(kMaxCoordinate_m) + " m");
    }
    int index = 0;
    for (long r = 0; r < rows; ++r) {
      for (long c = 0; c < cols; ++c) {
        const double pos[3] = {origin[0] + c * spacing, origin[1] + r * spacing, origin[2]};
        instantiate(worldbody, e, "vehicles", prefix + std::to_string(index++), pos, yaw(e));
      }
    }
  }

  const char* required(XMLElement* e, const char* attr) {
    const char* v = e->Attribute(attr);
    if (v == nullptr || *v == '\0') {
      fail(world_path_, e->GetLineNum(), std::string("<") + e->Name() + "> needs " + attr + "=");
    }
    return v;
  }

  std::vector<double> offset(XMLElement* e) const {
    double p[3];
    vec3_attr(e, "pos", p, world_path_);
    return {p[0], p[1], p[2]};
  }
  double yaw(XMLElement* e) const {
    return number_attr(e, "yaw_deg", 0.0, -kMaxYaw_deg, kMaxYaw_deg, world_path_) * kPi / 180.0;
  }

  // adding `more` vehicles keeps the world within kMaxVehicles, or fails saying what to do instead
  void check_vehicle_count(XMLElement* at, long more) {
    if (vehicles_ + more <= kMaxVehicles) return;
    fail(world_path_, at->GetLineNum(),
         "this world would have " + std::to_string(vehicles_ + more) + " vehicles; one server simulates at "
         "most " + std::to_string(kMaxVehicles) + " (MuJoCo 2.2 cannot allocate the state of a few thousand): "
         "split the fleet across several servers, each with its own world and ports");
  }

  void instantiate(XMLElement* worldbody, XMLElement* at, const std::string& kind,
                   const std::string& name, const std::vector<double>& pos, double yaw_rad) {
    instantiate(worldbody, at, kind, name, pos.data(), yaw_rad);
  }

  Template& load_template(XMLElement* at, const std::string& kind) {
    const char* type = required(at, "type");
    const std::string key = kind + "/" + type;
    auto it = templates_.find(key);
    if (it != templates_.end()) return it->second;

    const fs::path path = fs::path(options_.models_dir) / kind / (std::string(type) + ".xml");
    if (!fs::exists(path)) {
      std::string known;
      if (fs::is_directory(fs::path(options_.models_dir) / kind)) {
        for (const auto& f : fs::directory_iterator(fs::path(options_.models_dir) / kind)) {
          if (f.path().extension() == ".xml") known += " " + f.path().stem().string();
        }
      }
      fail(world_path_, at->GetLineNum(),
           "unknown " + kind.substr(0, kind.size() - 1) + " type '" + type + "' (known:" + known + ")");
    }
    Template t;
    t.path = path.string();
    t.doc = load_xml(t.path);
    XMLElement* root = t.doc->RootElement();
    absolutize_asset_paths(root, path.parent_path(), t.path);
    XMLElement* wb = root->FirstChildElement("worldbody");
    t.body = wb ? wb->FirstChildElement("body") : nullptr;
    if (t.body == nullptr || t.body->Attribute("name") == nullptr) {
      fail(t.path, root->GetLineNum(), "a template needs a named <body> in its <worldbody>");
    }
    t.name = t.body->Attribute("name");
    t.angle = compiler_attr(root, "angle", "degree");
    if (XMLElement* size = root->FirstChildElement("size")) t.nuser_site = size->IntAttribute("nuser_site", 0);
    if (t.angle != world_angle_) {
      fail(world_path_, at->GetLineNum(),
           "the world uses <compiler angle=\"" + world_angle_ + "\"> but " + t.path + " uses \"" +
               t.angle + "\": declare <compiler angle=\"" + t.angle + "\"/> in the world");
    }
    return templates_.emplace(key, std::move(t)).first->second;
  }

  // collision="..." of a vehicle element: the local geom-name prefixes whose geoms stay collidable, or
  // empty for "full" (the template as written). "lean" stands for "hull gear". Each word must name some
  // geom of the template, and the set must keep landing gear (without it the vehicle falls through the
  // ground); errors name the world file and line and list the template's geoms.
  std::vector<std::string> collision_set(XMLElement* at, const Template& t) {
    const char* text = at->Attribute("collision");
    if (text == nullptr) return {};
    std::vector<std::string> words;
    std::istringstream in(text);
    for (std::string w; in >> w;) {
      if (w == "lean") {
        words.insert(words.end(), {"hull", "gear"});
      } else {
        words.push_back(w);
      }
    }
    if (words.size() == 1 && words[0] == "full") return {};
    std::vector<std::string> geoms;
    collect_geom_names(t.body, &geoms);
    std::string known;
    for (const std::string& g : geoms) known += " " + g;
    if (words.empty() || words.size() > kMaxCollisionWords) {
      fail(world_path_, at->GetLineNum(),
           "collision=\"" + std::string(text) + "\" must be full, lean, or 1 to " +
               std::to_string(kMaxCollisionWords) + " geom-name prefixes of '" + required(at, "type") +
               "' (geoms:" + known + ")");
    }
    bool gear = false;
    for (const std::string& w : words) {
      bool matched = false;
      for (const std::string& g : geoms) {
        if (g.rfind(w, 0) != 0) continue;
        matched = true;
        gear = gear || g.rfind("gear", 0) == 0;
      }
      if (!matched || w == "full") {
        fail(world_path_, at->GetLineNum(),
             "collision=\"" + std::string(text) + "\": '" + w + "' names no geom of '" + required(at, "type") +
                 "' (full and lean stand alone; geoms:" + known + ")");
      }
    }
    if (!gear) {
      fail(world_path_, at->GetLineNum(),
           "collision=\"" + std::string(text) + "\" leaves out the landing gear (gear* geoms): the vehicle "
           "would fall through the ground");
    }
    return words;
  }

  static void collect_geom_names(const XMLElement* body, std::vector<std::string>* out) {
    for (const XMLElement* c = body->FirstChildElement(); c; c = c->NextSiblingElement()) {
      const std::string tag = c->Name();
      if (tag == "geom" && c->Attribute("name") != nullptr) out->push_back(c->Attribute("name"));
      if (tag == "body") collect_geom_names(c, out);
    }
  }

  // geoms (of the clone, before its names are prefixed) outside the set get no collision bits
  static void apply_collision_set(XMLElement* body, const std::vector<std::string>& keep) {
    for (XMLElement* c = body->FirstChildElement(); c; c = c->NextSiblingElement()) {
      const std::string tag = c->Name();
      if (tag == "body") apply_collision_set(c, keep);
      if (tag != "geom") continue;
      const char* n = c->Attribute("name");
      const bool kept = n != nullptr && std::any_of(keep.begin(), keep.end(), [n](const std::string& w) {
                          return std::string_view(n).substr(0, w.size()) == w;
                        });
      if (kept) continue;
      c->SetAttribute("contype", 0);
      c->SetAttribute("conaffinity", 0);
    }
  }

  void instantiate(XMLElement* worldbody, XMLElement* at, const std::string& kind,
                   const std::string& name, const double pos[3], double yaw_rad) {
    if (name.find('/') != std::string::npos || name.find(':') != std::string::npos) {
      fail(world_path_, at->GetLineNum(), "name '" + name + "' may not contain '/' or ':'");
    }
    if (!names_.insert(name).second) {
      fail(world_path_, at->GetLineNum(), "duplicate vehicle or object name '" + name + "'");
    }
    Template& t = load_template(at, kind);
    merge_globals(t);
    if (kind == "vehicles") {
      ++vehicles_;
      vehicle_names_.push_back(name);
    }

    // clone the body, prefix every name inside it, and place it
    XMLElement* body = t.body->DeepClone(world_.get())->ToElement();
    if (kind == "vehicles") {
      if (const std::vector<std::string> keep = collision_set(at, t); !keep.empty()) {
        apply_collision_set(body, keep);
      }
    } else if (at->Attribute("collision") != nullptr) {
      fail(world_path_, at->GetLineNum(), "collision= applies to vehicles only");
    }
    prefix_names(body, name + "/");
    body->SetAttribute("name", name.c_str());
    double base[3];
    vec3_attr(t.body, "pos", base, t.path);
    const double p[3] = {pos[0] + base[0], pos[1] + base[1], pos[2] + base[2]};
    body->SetAttribute("pos", join3(p).c_str());
    if (yaw_rad != 0.0) {
      std::ostringstream q;
      q.precision(12);
      q << std::cos(yaw_rad / 2) << " 0 0 " << std::sin(yaw_rad / 2);
      body->DeleteAttribute("euler");
      body->SetAttribute("quat", q.str().c_str());
    }
    // insert where the uavsim_* element stands, so the world keeps its order
    if (XMLNode* prev = at->PreviousSibling()) {
      worldbody->InsertAfterChild(prev, body);
    } else {
      worldbody->InsertFirstChild(body);
    }

    // per-instance custom elements: the template's name in uavsim:* names becomes the instance name
    XMLElement* custom_src = t.doc->RootElement()->FirstChildElement("custom");
    if (custom_src != nullptr) {
      XMLElement* custom = child_or_create(*world_, world_->RootElement(), "custom");
      for (XMLElement* c = custom_src->FirstChildElement(); c; c = c->NextSiblingElement()) {
        XMLElement* copy = c->DeepClone(world_.get())->ToElement();
        if (const char* n = copy->Attribute("name")) {
          copy->SetAttribute("name", rename_custom(n, t.name, name).c_str());
        }
        custom->InsertEndChild(copy);
      }
    }
    copy_sensors(t, name);
  }

  // per-instance sensors (e.g. touch sensors on a vehicle's pad sites): the sensor's name and the
  // element it reads (site, body, joint, ...) take the instance prefix like every name in the body
  void copy_sensors(const Template& t, const std::string& name) {
    for (XMLElement* src = t.doc->RootElement()->FirstChildElement("sensor"); src;
         src = src->NextSiblingElement("sensor")) {
      XMLElement* sensor = child_or_create(*world_, world_->RootElement(), "sensor");
      for (XMLElement* c = src->FirstChildElement(); c; c = c->NextSiblingElement()) {
        XMLElement* copy = c->DeepClone(world_.get())->ToElement();
        for (const char* attr : {"name", "site", "body", "joint", "objname", "actuator", "tendon"}) {
          if (const char* v = copy->Attribute(attr)) copy->SetAttribute(attr, (name + "/" + v).c_str());
        }
        sensor->InsertEndChild(copy);
      }
    }
  }

  static void prefix_names(XMLElement* e, const std::string& prefix) {
    if (const char* n = e->Attribute("name")) e->SetAttribute("name", (prefix + n).c_str());
    for (XMLElement* c = e->FirstChildElement(); c; c = c->NextSiblingElement()) {
      prefix_names(c, prefix);
    }
  }

  // "uavsim:quad:drag_lin" -> "uavsim:uav0:drag_lin"; "uavsim:vehicle:quad" -> "uavsim:vehicle:uav0"
  static std::string rename_custom(const std::string& n, const std::string& from,
                                   const std::string& to) {
    std::string out;
    std::istringstream s(n);
    std::string part;
    bool first = true;
    while (std::getline(s, part, ':')) {
      out += (first ? "" : ":") + (part == from ? to : part);
      first = false;
    }
    return out;
  }

  // copy a template's default classes and assets into the world, once per template
  void merge_globals(Template& t) {
    if (t.globals_merged) return;
    t.globals_merged = true;
    XMLElement* root = world_->RootElement();
    XMLElement* troot = t.doc->RootElement();
    if (XMLElement* tdef = troot->FirstChildElement("default")) {
      XMLElement* def = child_or_create(*world_, root, "default", true);
      for (XMLElement* c = tdef->FirstChildElement("default"); c; c = c->NextSiblingElement("default")) {
        def->InsertEndChild(c->DeepClone(world_.get()));
      }
    }
    for (XMLElement* tasset = troot->FirstChildElement("asset"); tasset;
         tasset = tasset->NextSiblingElement("asset")) {
      XMLElement* asset = child_or_create(*world_, root, "asset");
      for (XMLElement* c = tasset->FirstChildElement(); c; c = c->NextSiblingElement()) {
        asset->InsertEndChild(c->DeepClone(world_.get()));
      }
    }
    nuser_site_ = std::max(nuser_site_, t.nuser_site);
  }

  // uavsim_* elements anywhere but directly under <worldbody> are errors, not silently ignored
  void check_nested(XMLElement* e) {
    for (XMLElement* c = e->FirstChildElement(); c; c = c->NextSiblingElement()) {
      if (e == world_->RootElement() && std::string(c->Name()) != "worldbody") continue;
      if (std::string(c->Name()).rfind("uavsim_", 0) == 0) {
        fail(world_path_, c->GetLineNum(),
             std::string("<") + c->Name() + "> must be a direct child of <worldbody>");
      }
      check_nested(c);
    }
  }

  // Why a world cannot be split into shards ("" if it can): anything that moves other than the vehicles, or
  // that ties model elements together across vehicles (model-wide sections indexed by the whole model).
  std::string unshardable(XMLElement* root) const {
    for (const char* section : {"sensor", "actuator", "tendon", "equality", "contact", "keyframe"}) {
      for (XMLElement* e = root->FirstChildElement(section); e; e = e->NextSiblingElement(section)) {
        if (e->FirstChildElement() != nullptr) return std::string("it has <") + section + "> elements";
      }
    }
    const std::set<std::string> vehicles(vehicle_names_.begin(), vehicle_names_.end());
    for (XMLElement* wb = root->FirstChildElement("worldbody"); wb; wb = wb->NextSiblingElement("worldbody")) {
      for (XMLElement* b = wb->FirstChildElement("body"); b; b = b->NextSiblingElement("body")) {
        const char* name = b->Attribute("name");
        if (name != nullptr && vehicles.count(name) != 0) continue;
        if (const std::string moving = moving_body(b); !moving.empty()) {
          return "body '" + moving + "' moves and is not a vehicle";
        }
      }
    }
    return "";
  }

  // the name of the first body in this subtree with a joint or a mocap pose, or ""
  static std::string moving_body(const XMLElement* body) {
    const bool moves = body->FirstChildElement("joint") != nullptr || body->FirstChildElement("freejoint") != nullptr ||
                       body->BoolAttribute("mocap", false);
    if (moves) return body->Attribute("name") ? body->Attribute("name") : "(unnamed)";
    for (const XMLElement* c = body->FirstChildElement("body"); c; c = c->NextSiblingElement("body")) {
      if (std::string m = moving_body(c); !m.empty()) return m;
    }
    return "";
  }

  // A world that nothing renders (a sharded one: the server refuses cameras on it; or
  // ComposeOptions::vehicle_visual_geoms off) needs only the geoms that collide: the vehicles'
  // visual-only geoms (contype = conaffinity = 0; 17 of a lean quad's 20) go, which MuJoCo would
  // otherwise place every step. Only in bodies whose mass is given by an <inertial> (and unless the
  // compiler takes inertia from geoms), so that no body's dynamics change.
  void strip_visual_geoms(XMLElement* root) const {
    if (compiler_attr(root, "inertiafromgeom", "auto") == "true") return;
    std::map<std::string, std::pair<int, int>> bits;  // default class -> (contype, conaffinity)
    for (XMLElement* d = root->FirstChildElement("default"); d; d = d->NextSiblingElement("default")) {
      collect_default_bits(d, {1, 1}, &bits);
    }
    const std::set<std::string> vehicles(vehicle_names_.begin(), vehicle_names_.end());
    for (XMLElement* wb = root->FirstChildElement("worldbody"); wb; wb = wb->NextSiblingElement("worldbody")) {
      for (XMLElement* b = wb->FirstChildElement("body"); b; b = b->NextSiblingElement("body")) {
        if (const char* n = b->Attribute("name"); n != nullptr && vehicles.count(n) != 0) {
          strip_visual_geoms(b, "main", bits);
        }
      }
    }
  }

  // MuJoCo's default classes: a nested class starts from its parent's values; the top one is "main"
  static void collect_default_bits(const XMLElement* def, std::pair<int, int> inherited,
                                   std::map<std::string, std::pair<int, int>>* out) {
    std::pair<int, int> b = inherited;
    if (const XMLElement* g = def->FirstChildElement("geom")) {
      b = {g->IntAttribute("contype", b.first), g->IntAttribute("conaffinity", b.second)};
    }
    const char* cls = def->Attribute("class");
    (*out)[cls != nullptr ? cls : "main"] = b;
    for (const XMLElement* c = def->FirstChildElement("default"); c; c = c->NextSiblingElement("default")) {
      collect_default_bits(c, b, out);
    }
  }

  static void strip_visual_geoms(XMLElement* body, const std::string& childclass,
                                 const std::map<std::string, std::pair<int, int>>& bits) {
    const std::string cls = body->Attribute("childclass") ? body->Attribute("childclass") : childclass;
    const bool inertial = body->FirstChildElement("inertial") != nullptr;
    for (XMLElement* c = body->FirstChildElement(); c;) {
      XMLElement* next = c->NextSiblingElement();
      const std::string tag = c->Name();
      if (tag == "body") strip_visual_geoms(c, cls, bits);
      if (tag == "geom" && inertial) {
        const auto it = bits.find(c->Attribute("class") ? c->Attribute("class") : cls);
        const std::pair<int, int> b = it != bits.end() ? it->second : std::pair<int, int>{1, 1};
        if (c->IntAttribute("contype", b.first) == 0 && c->IntAttribute("conaffinity", b.second) == 0) {
          body->DeleteChild(c);
        }
      }
      c = next;
    }
  }

  static int auto_shard_count() {
    const unsigned hw = std::thread::hardware_concurrency();
    return static_cast<int>(std::clamp(hw, 1u, static_cast<unsigned>(kMaxAutoShards)));
  }

  // takes the named vehicles' bodies and their custom elements (uavsim:vehicle:NAME, uavsim:NAME:*) out
  static void remove_vehicles(XMLElement* root, const std::set<std::string>& names) {
    for (XMLElement* wb = root->FirstChildElement("worldbody"); wb; wb = wb->NextSiblingElement("worldbody")) {
      for (XMLElement* b = wb->FirstChildElement("body"); b;) {
        XMLElement* next = b->NextSiblingElement("body");
        if (const char* n = b->Attribute("name"); n != nullptr && names.count(n) != 0) wb->DeleteChild(b);
        b = next;
      }
    }
    for (XMLElement* custom = root->FirstChildElement("custom"); custom;
         custom = custom->NextSiblingElement("custom")) {
      for (XMLElement* c = custom->FirstChildElement(); c;) {
        XMLElement* next = c->NextSiblingElement();
        if (names.count(custom_owner(c->Attribute("name"))) != 0) custom->DeleteChild(c);
        c = next;
      }
    }
  }

  // "uavsim:vehicle:uav3" and "uavsim:uav3:drag_lin" -> "uav3"; anything else -> ""
  static std::string custom_owner(const char* name) {
    if (name == nullptr) return "";
    const std::string_view n = name;
    constexpr std::string_view kPrefix = "uavsim:", kVehicle = "uavsim:vehicle:";
    if (n.substr(0, kVehicle.size()) == kVehicle) return std::string(n.substr(kVehicle.size()));
    if (n.substr(0, kPrefix.size()) != kPrefix) return "";
    const std::string_view rest = n.substr(kPrefix.size());
    const size_t colon = rest.find(':');
    return colon == std::string_view::npos ? "" : std::string(rest.substr(0, colon));
  }

  static std::string print(const XMLDocument& doc) {
    tinyxml2::XMLPrinter printer;
    doc.Print(&printer);
    return printer.CStr();
  }

  // sizes the composed model needs: user data slots of the rotor sites, contact and constraint buffers
  // (MuJoCo 2.2's defaults, 100 contacts and 500 constraint rows, drop contacts beyond a few vehicles),
  // the offscreen buffer. n: the vehicles and objects in this model (a shard's own), of `shards` shards.
  void finish(XMLDocument& doc, long n, int shards = 1) {
    XMLElement* root = doc.RootElement();
    XMLElement* size = child_or_create(doc, root, "size", true);
    if (nuser_site_ > 0) {
      size->SetAttribute("nuser_site", std::max(nuser_site_, size->IntAttribute("nuser_site", 0)));
    }
    if (size->Attribute("nconmax") == nullptr) size->SetAttribute("nconmax", static_cast<int>(100 + 8 * n));
    if (size->Attribute("njmax") == nullptr) size->SetAttribute("njmax", auto_njmax(n, shards));
    XMLElement* visual = child_or_create(doc, root, "visual");
    XMLElement* global = child_or_create(doc, visual, "global");
    global->SetAttribute("offwidth",
                         std::max(options_.offscreen_width_px, global->IntAttribute("offwidth", 0)));
    global->SetAttribute("offheight",
                         std::max(options_.offscreen_height_px, global->IntAttribute("offheight", 0)));
  }

  // Constraint rows for what can be in contact at once. A vehicle on its gear needs up to 4 contacts x
  // 4 pyramid rows; vehicles at rest are parked (physics/world.hpp) and flying ones touch nothing, so
  // only those taking off, landing or armed on the ground need rows. Contacts are cheap (nconmax: every
  // vehicle), rows are not: MuJoCo 2.2 allocates per row a dense Jacobian row of nv doubles twice (efc_J,
  // efc_JT, with column indices) and a dense row of njmax (efc_AR), in one buffer whose size is an int:
  // bytes = njmax (24 nv + 12 njmax) must stay well below 2^31 (njmax >= 11000 fails for 1000 quads).
  // So: every vehicle on its gear at once up to a buffer of 1 GiB, then as many as fit. The
  // budget is the world's: each of `shards` shards gets its share (and, as the buffer grows with the square
  // of the rows, the shards together hold more rows in it than one model would).
  static int auto_njmax(long vehicles, int shards) {
    const double row_budget_bytes = 1.0 * (1u << 30) / shards;
    constexpr long kRowsPerGroundedVehicle = 16;
    const double nv = 6.0 * static_cast<double>(vehicles) + 60.0;  // free joints, and some for objects
    // 12 r^2 + 24 nv r = budget
    const double fit = (-24.0 * nv + std::sqrt(576.0 * nv * nv + 48.0 * row_budget_bytes)) / 24.0;
    const double wanted = 500.0 + static_cast<double>(kRowsPerGroundedVehicle * vehicles);
    return static_cast<int>(std::min(wanted, std::floor(fit)));
  }

  std::string world_path_;
  ComposeOptions options_;
  std::unique_ptr<XMLDocument> world_;
  std::string world_angle_;
  std::map<std::string, Template> templates_;
  std::set<std::string> names_;
  std::vector<std::string> vehicle_names_;  // in world order
  long vehicles_ = 0;
  int nuser_site_ = 0;
};

}  // namespace

std::string compose_world(const std::string& world_path, const ComposeOptions& options) {
  ComposeOptions o = options;
  if (o.models_dir.empty()) o.models_dir = default_models_dir();
  return Composer(world_path, o).compose();
}

std::vector<std::string> compose_world_shards(const std::string& world_path, const ComposeOptions& options,
                                              int shards) {
  ComposeOptions o = options;
  if (o.models_dir.empty()) o.models_dir = default_models_dir();
  return Composer(world_path, o).compose_shards(shards);
}

common::ModelsDir find_models_dir(const std::string& option) {
#ifdef UAVSIM_MODELS_DIR
  return common::find_models_dir(option, UAVSIM_MODELS_DIR);
#else
  return common::find_models_dir(option, "");
#endif
}

std::string default_models_dir() { return find_models_dir("").path; }

}  // namespace uavsim::server::physics
