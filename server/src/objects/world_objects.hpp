// The object factory: finds the world objects of a loaded world and adds them to the simulation.
//   - trucks:   custom text uavsim:object:NAME = "truck"    (models/objects/truck.xml; see truck.hpp)
//   - balloons: custom text uavsim:object:NAME = "balloon"  (models/objects/balloon.xml; balloons.hpp)
//   - gimbals:  custom text uavsim:gimbal:BODY = "VEHICLE MODE"                          (gimbal.hpp)
// The templates carry the uavsim:object text, so a world only writes <uavsim_object type=... name=.../>.
#pragma once

#include <vector>

#include "objects/balloons.hpp"
#include "objects/gimbal.hpp"
#include "objects/truck.hpp"
#include "sim/simulation.hpp"

namespace uavsim::server::objects {

// Non-owning views of the objects added (the simulation owns them); empty when the world has none.
struct ObjectSet {
  std::vector<Truck*> trucks;
  BalloonField* balloons = nullptr;
  GimbalSet* gimbals = nullptr;
};

// Creates the objects the world declares, owned by sim, not yet in its step schedule. Throws
// physics::WorldError naming the object and the custom field for bad parameters (a startup error).
// Before the loop starts.
ObjectSet create_world_objects(sim::Simulation& sim);
// Registers set's objects in sim's step schedule (Simulation::schedule_object), trucks in the world's
// order, then the balloons, then the gimbals. Before the loop starts.
void schedule_world_objects(sim::Simulation& sim, const ObjectSet& set);
// Both: the objects created and registered. Before the loop starts.
ObjectSet add_world_objects(sim::Simulation& sim);

}  // namespace uavsim::server::objects
