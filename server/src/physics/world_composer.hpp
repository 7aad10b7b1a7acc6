// World composition: turns a uavsim world file into plain MuJoCo 2.2 MJCF.
// MuJoCo 2.2 has no <replicate>, <attach> or mjSpec, so vehicles and objects are templates (models/vehicles,
// models/objects) that the composer instantiates with tinyxml2, prefixing every name. A world file is MJCF
// plus these elements inside <worldbody>:
//   <uavsim_vehicle type="quad" name="uav0" pos="0 0 0" yaw_deg="0"/>            one vehicle
//   <uavsim_grid type="quad" prefix="uav" rows="10" cols="10" spacing="4" pos="0 0 0"/>   rows*cols vehicles
//   <uavsim_object type="balloon" name="balloon0" pos="..."/>                   one object from models/objects
// A vehicle element may choose the template's collision set: collision="full" (default: as written),
// "lean" (hull and landing gear: hull* and gear* geoms) or geom-name prefixes ("lean blade", "hull gear
// prop"); the other geoms get contype = conaffinity = 0 (still drawn, never touching anything).
// <include file="..."/> is inlined here (MuJoCo would resolve it relative to the composed file otherwise), and
// every asset file path is made absolute, so the composed text loads from anywhere (--write-world).
// Meshes in formats MuJoCo 2.2 does not read are converted (assets/mesh_convert.hpp) into a cache directory
// and the <mesh file=...> points at the converted file.
// This is the one place that would change on MuJoCo 3.x (mjSpec and <attach> replace it).
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

#include "uavsim/common/install_paths.hpp"

namespace uavsim::server::physics {

// A startup error in a world or template file; what() names the file and line.
class WorldError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct ComposeOptions {
  std::string models_dir;  // where vehicles/ and objects/ templates live
  int offscreen_width_px = 1280;   // <visual><global offwidth/offheight>: the largest camera frame
  int offscreen_height_px = 960;
  // Where meshes MuJoCo 2.2 cannot read (COLLADA, glTF, FBX, PLY, ASCII STL, ...) are converted to, as
  // OBJ files named by the SHA-256 of the source's content (so a second load reuses them). Empty: per
  // user, $XDG_CACHE_HOME/uavsim/meshes, else ~/.cache/uavsim/meshes.
  std::string mesh_cache_dir;
  // false for a world nothing will render (no camera, no recording): the vehicles' visual-only
  // geoms (contype = conaffinity = 0, in bodies whose mass an <inertial> gives) are left out, as in
  // every physics shard. MuJoCo would place each of them at every step for nothing (a lean quad has
  // 20 geoms, 3 of which collide); no body's mass, inertia or contacts change. (A vehicle's
  // visual-only geoms never block radio either way: physics/line_of_sight.hpp.)
  bool vehicle_visual_geoms = true;
};

// Reads world_path, expands includes, vehicles and objects, and returns standalone MJCF text.
// Throws WorldError naming the file and line for malformed XML, an unknown vehicle or object type,
// a missing or duplicate name, or a bad attribute; naming the world file and the mesh for a mesh file
// that is missing or cannot be converted, or a cache directory that cannot be written.
std::string compose_world(const std::string& world_path, const ComposeOptions& options);

// Physics shards (physics/world.hpp): the world's vehicles split into `shards` contiguous blocks in world order
// (shard k holds vehicles [k N / shards, (k + 1) N / shards)), each block composed with the whole static
// scene into its own standalone MJCF. Each shard's contact and constraint buffers are sized for its own
// vehicles (nconmax, njmax unless the world sets them: then every shard gets the world's values).
// shards = 0 is auto: one shard per hardware thread (at most 8) for a world of 200 or more vehicles that
// can be sharded, else 1. One shard gives exactly compose_world's text.
// A world can be sharded only if nothing but its vehicles moves (no joint or mocap body outside a vehicle)
// and it has no model-wide <sensor>, <actuator>, <tendon>, <equality>, <contact> or <keyframe> entries;
// otherwise, and for shards outside 1..kMaxPhysicsShards or more shards than vehicles, WorldError says why.
constexpr int kMaxPhysicsShards = 64;
std::vector<std::string> compose_world_shards(const std::string& world_path, const ComposeOptions& options,
                                              int shards);

// The shipped models of this build: option (--models-dir, "" when not given), else
// UAVSIM_MODELS_DIR in the environment, else PREFIX/share/uavsim/models beside an installed
// PREFIX/bin, else the source tree the build came from (common::find_models_dir). Thread-safe.
common::ModelsDir find_models_dir(const std::string& option);
// find_models_dir("").path: where vehicles/, objects/ and worlds/ are when no option says.
std::string default_models_dir();

}  // namespace uavsim::server::physics
