// Segmentation labels: which object and which class every geom of a world belongs to, for the
// segmentation images of the cameras (docs/protocol.md "Camera frames"). Ground truth for scoring
// and training; the missions decide from colour and grey alone.
//
// Classes are fixed (their ids never change); objects are numbered from 1 in the model's geom
// order, so ids are the same in every frame and every run of one world:
//   vehicle  every geom of a vehicle's bodies (and of gimbal bodies bound to it): object VEHICLE
//   balloon  the sphere of a balloon object (uavsim:object:NAME = balloon): object NAME
//   pole     the pole it stands on: object NAME/pole
//   truck    every geom of a truck object but its marker: object NAME
//   marker   the truck's landing marker (geom NAME/marker): object NAME/marker
//   ground   a plane of the world body: object GEOMNAME (or "ground")
//   scenery  everything else: a world-body geom is its own object, another body's geoms are
//            its root's
// Object 0 and class 0 are "none": a pixel where nothing was hit.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <utility>
#include <vector>

struct mjModel_;

namespace uavsim::server::render {

enum class SegmentClass : uint16_t {
  kNone = 0,
  kGround = 1,
  kVehicle = 2,
  kBalloon = 3,
  kPole = 4,
  kTruck = 5,
  kMarker = 6,
  kScenery = 7,
};
inline constexpr int kSegmentClassCount = 8;
// "none", "ground", "vehicle", ... Thread-safe.
const char* segment_class_name(SegmentClass c);

struct SegmentObject {
  uint16_t id = 0;
  std::string name;
  SegmentClass cls = SegmentClass::kNone;
};

// Per geom: its object's id and its class; objects[i] has id i (objects[0] is "none").
struct SegmentationLabels {
  std::vector<uint16_t> geom_object;
  std::vector<SegmentClass> geom_class;
  std::vector<SegmentObject> objects;
};

// What the application knows about vehicles and gimbals (no MuJoCo types): which camera belongs to
// which vehicle (camera_setup.hpp), which geoms are a vehicle's here.
struct CameraOwners {
  // body id of vehicle i's root, its name
  std::vector<std::pair<int, std::string>> vehicle_root_bodies;
  // gimbal body id -> vehicle index
  std::map<int, int> gimbal_body_vehicle;
};

// The labels of every geom of m. Throws std::invalid_argument if the world has more objects than a
// 16-bit id holds (65535). Thread-safe (reads m only).
SegmentationLabels label_geoms(const mjModel_* m, const CameraOwners& owners);

}  // namespace uavsim::server::render
