#include "physics/touch_sensors.hpp"

#include <mujoco/mujoco.h>

namespace uavsim::server::physics {

std::vector<std::vector<TouchSensor>> vehicle_touch_sensors(const World& world) {
  const mjModel* m = world.model();
  std::vector<std::vector<TouchSensor>> out(world.vehicles().size());
  for (int s = 0; s < m->nsensor; ++s) {
    if (m->sensor_type[s] != mjSENS_TOUCH || m->sensor_objtype[s] != mjOBJ_SITE) continue;
    const int root = m->body_rootid[m->site_bodyid[m->sensor_objid[s]]];
    for (size_t v = 0; v < world.vehicles().size(); ++v) {
      if (world.vehicles()[v].body_id != root) continue;
      const char* n = mj_id2name(m, mjOBJ_SENSOR, s);
      std::string name = n != nullptr ? n : "touch" + std::to_string(s);
      const size_t slash = name.rfind('/');
      if (slash != std::string::npos) name = name.substr(slash + 1);
      out[v].push_back(TouchSensor{name, m->sensor_adr[s], v, 0.0});
    }
  }
  for (size_t v = 0; v < out.size(); ++v) {
    const double weight_n = world.vehicles()[v].airframe.mass_kg * -m->opt.gravity[2];
    for (TouchSensor& t : out[v]) t.parked_force_n = weight_n / static_cast<double>(out[v].size());
  }
  return out;
}

double touch_force_n(const World& world, const TouchSensor& sensor) {
  if (world.parked(sensor.vehicle)) return sensor.parked_force_n;
  return world.data()->sensordata[sensor.sensor_adr];
}

}  // namespace uavsim::server::physics
