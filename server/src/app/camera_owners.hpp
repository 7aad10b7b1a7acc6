// Which of a world's cameras and geoms belong to which vehicle: the vehicles' root bodies and the
// gimbals carrying their cameras, as camera discovery and the segmentation labels want them
// (render/segmentation.hpp). The server, its tests and its benchmarks build them the same way.
#pragma once

#include "objects/world_objects.hpp"
#include "physics/world.hpp"
#include "render/segmentation.hpp"

namespace uavsim::server::app {

// The owners in world with objects' gimbals (none when objects has no gimbal set). Before the loop
// starts, or on the loop thread.
render::CameraOwners camera_owners(const physics::World& world, const objects::ObjectSet& objects);

}  // namespace uavsim::server::app
