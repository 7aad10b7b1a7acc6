#include "render/segmentation.hpp"

#include <mujoco/mujoco.h>

#include <limits>
#include <stdexcept>

namespace uavsim::server::render {

namespace {

constexpr const char* kObjectPrefix = "uavsim:object:";

// the object type of root body `root` from its uavsim:object:NAME text ("" if none)
std::string object_type(const mjModel* m, const std::string& root_name) {
  const std::string text = kObjectPrefix + root_name;
  const int t = mj_name2id(m, mjOBJ_TEXT, text.c_str());
  return t < 0 ? std::string() : std::string(m->text_data + m->text_adr[t]);
}

// the geom's name without its instance prefix "ROOT/" ("" for an unnamed geom)
std::string local_name(const char* name, const std::string& root_name) {
  if (name == nullptr) return {};
  const std::string n = name;
  const std::string prefix = root_name + "/";
  return n.compare(0, prefix.size(), prefix) == 0 ? n.substr(prefix.size()) : n;
}

}  // namespace

const char* segment_class_name(SegmentClass c) {
  switch (c) {
    case SegmentClass::kNone:
      return "none";
    case SegmentClass::kGround:
      return "ground";
    case SegmentClass::kVehicle:
      return "vehicle";
    case SegmentClass::kBalloon:
      return "balloon";
    case SegmentClass::kPole:
      return "pole";
    case SegmentClass::kTruck:
      return "truck";
    case SegmentClass::kMarker:
      return "marker";
    case SegmentClass::kScenery:
      return "scenery";
  }
  return "?";
}

SegmentationLabels label_geoms(const mjModel_* model, const CameraOwners& owners) {
  const mjModel* m = model;
  SegmentationLabels labels;
  labels.objects.push_back({0, "none", SegmentClass::kNone});
  std::map<std::string, uint16_t> by_name;  // object name -> id
  auto object = [&](const std::string& name, SegmentClass cls) -> uint16_t {
    if (auto it = by_name.find(name); it != by_name.end()) return it->second;
    if (labels.objects.size() > std::numeric_limits<uint16_t>::max()) {
      throw std::invalid_argument("segmentation: the world has more than 65535 objects");
    }
    const auto id = static_cast<uint16_t>(labels.objects.size());
    labels.objects.push_back({id, name, cls});
    by_name.emplace(name, id);
    return id;
  };

  // vehicle index of a body: its root is a vehicle's root, or it is a gimbal bound to a vehicle
  auto vehicle_of = [&](int body) -> int {
    if (auto g = owners.gimbal_body_vehicle.find(body); g != owners.gimbal_body_vehicle.end())
      return g->second;
    const int root = m->body_rootid[body];
    for (size_t v = 0; v < owners.vehicle_root_bodies.size(); ++v) {
      if (root != 0 && owners.vehicle_root_bodies[v].first == root) return static_cast<int>(v);
    }
    return -1;
  };

  for (int g = 0; g < m->ngeom; ++g) {
    const int body = m->geom_bodyid[g];
    const int root = m->body_rootid[body];
    const char* geom_name = mj_id2name(m, mjOBJ_GEOM, g);
    SegmentClass cls = SegmentClass::kScenery;
    std::string name;
    if (const int v = vehicle_of(body);
        v >= 0 && static_cast<size_t>(v) < owners.vehicle_root_bodies.size()) {
      cls = SegmentClass::kVehicle;
      name = owners.vehicle_root_bodies[static_cast<size_t>(v)].second;
    } else if (root == 0) {
      // the world body: ground planes and scenery, one object per geom
      cls = m->geom_type[g] == mjGEOM_PLANE ? SegmentClass::kGround : SegmentClass::kScenery;
      name = geom_name != nullptr && geom_name[0] != '\0'
                 ? std::string(geom_name)
                 : (cls == SegmentClass::kGround ? "ground" : "geom" + std::to_string(g));
    } else {
      const char* root_cname = mj_id2name(m, mjOBJ_BODY, root);
      const std::string root_name =
          root_cname != nullptr ? root_cname : "body" + std::to_string(root);
      const std::string type = object_type(m, root_name);
      const std::string local = local_name(geom_name, root_name);
      name = root_name;
      if (type == "balloon") {
        cls = local == "pole" ? SegmentClass::kPole : SegmentClass::kBalloon;
        if (cls == SegmentClass::kPole) name = root_name + "/pole";
      } else if (type == "truck") {
        cls = local == "marker" ? SegmentClass::kMarker : SegmentClass::kTruck;
        if (cls == SegmentClass::kMarker) name = root_name + "/marker";
      }
    }
    labels.geom_object.push_back(object(name, cls));
    labels.geom_class.push_back(cls);
  }
  return labels;
}

}  // namespace uavsim::server::render
