#include "app/camera_owners.hpp"

#include "objects/gimbal.hpp"

namespace uavsim::server::app {

render::CameraOwners camera_owners(const physics::World& world, const objects::ObjectSet& objects) {
  render::CameraOwners owners;
  for (const physics::VehicleBinding& v : world.vehicles())
    owners.vehicle_root_bodies.emplace_back(v.body_id, v.name);
  if (objects.gimbals != nullptr) {
    for (const objects::Gimbal& g : objects.gimbals->gimbals())
      owners.gimbal_body_vehicle[g.body_id] = g.vehicle;
  }
  return owners;
}

}  // namespace uavsim::server::app
