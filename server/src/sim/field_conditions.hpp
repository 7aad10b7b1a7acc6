// Field conditions (issue 16): what makes the simulated world as hard as the field — wind and
// gusts, sensor biases and drift, gimbal lag, camera noise and latency, balloon heights and sway,
// battery sag. One switch, realism "ideal" (the default: none of it, every result as before) or
// "field" (all of it with the defaults below), then each part can be set on its own (world file,
// command line, sim API). docs/results/field_conditions.md gives the reasoning behind each default.
#pragma once

#include <cmath>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "airframe/wind.hpp"

namespace uavsim::server::sim {

enum class Realism { kIdeal, kField };
const char* realism_name(Realism realism);  // "ideal", "field"
std::optional<Realism> realism_from_name(const std::string& name);

struct GimbalDynamicsParams {
  double time_const_s = 0.0;      // first-order lag of the stabilisation loop; 0: perfect gimbal
  double rate_max_rad_s = 0.0;    // slew-rate limit; 0: none
  double accel_max_rad_s2 = 0.0;  // slew-acceleration limit; 0: none
};

struct BalloonVariation {
  double height_spread_m =
      0.0;            // balloon tops uniform in nominal +- spread (per seed); 0: as modelled
  bool sway = false;  // balloons lean and sway in the wind on their poles
};

struct FieldConditions {
  Realism realism = Realism::kIdeal;
  airframe::WindParams wind;
  bool wind_from_seeded =
      false;  // the mean wind's direction is drawn from the seed (field default)
  double battery_resistance_ohm = 0.0;  // > 0: every vehicle's pack sags under load (airframe.hpp)
  GimbalDynamicsParams gimbal;
  BalloonVariation balloons;
  // sensor-model parameters (SIM_*) for every vehicle, before its own (world, --defaults) ones
  std::vector<std::pair<std::string, double>> sensor_params;
  // camera settings (render/camera_setup.hpp keys) for every camera, before the --camera overrides
  std::string camera_settings;
};

// The conditions of a realism level with its defaults: kIdeal is all off; kField is docs/results/
// field_conditions.md's set. Thread-safe (pure).
FieldConditions field_conditions(Realism realism);

}  // namespace uavsim::server::sim
