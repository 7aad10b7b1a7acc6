// A vehicle's MuJoCo touch sensors (e.g. the hexa's landing-pad microswitches,
// models/vehicles/hexa.xml): found once in the loaded model, read from mjData's sensordata after
// each step. Kept in physics/ because only physics/ includes mujoco.h. Loop-thread only, like the
// World it reads.
#pragma once

#include <string>
#include <vector>

#include "physics/world.hpp"

namespace uavsim::server::physics {

struct TouchSensor {
  std::string name;     // without the vehicle prefix ("uav0/pad0" -> "pad0")
  int sensor_adr = -1;  // into sensordata
  size_t vehicle = 0;
  // while the vehicle is parked (no contacts: physics/world.hpp) it rests on its pads: its weight shared
  // evenly among its touch sensors
  double parked_force_n = 0.0;
};

// Per vehicle (index as in World::vehicles()), the touch sensors on sites of that vehicle's bodies,
// in model order.
std::vector<std::vector<TouchSensor>> vehicle_touch_sensors(const World& world);

// The sensor's last reading: the normal force of the contacts inside its site's volume (N, >= 0); for a
// parked vehicle, its share of the vehicle's weight.
double touch_force_n(const World& world, const TouchSensor& sensor);

}  // namespace uavsim::server::physics
