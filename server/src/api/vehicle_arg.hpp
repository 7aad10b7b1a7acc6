// A request's vehicle field (docs/protocol.md: an index or a name), checked against the simulation:
// shared by the API's op groups so every op names vehicles and reports errors alike.
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "sim/simulation.hpp"

namespace uavsim::server::api {

// The vehicle index, or nullopt with *code ("bad_field" for a value that is neither an index nor a
// name, "unknown_vehicle" for one that names no vehicle) and *message. Loop thread only.
inline std::optional<size_t> vehicle_index(const sim::Simulation& sim, const nlohmann::json& value,
                                           std::string* code, std::string* message) {
  if (value.is_number_integer() || value.is_number_unsigned()) {
    const int64_t i = value.get<int64_t>();
    if (i >= 0 && static_cast<size_t>(i) < sim.vehicle_count()) return static_cast<size_t>(i);
  } else if (value.is_string()) {
    for (size_t i = 0; i < sim.vehicle_count(); ++i) {
      if (sim.vehicle_name(i) == value.get<std::string>()) return i;
    }
  } else {
    *code = "bad_field";
    *message = "a vehicle is an index or a name";
    return std::nullopt;
  }
  *code = "unknown_vehicle";
  *message =
      "no vehicle " + value.dump() + " (" + std::to_string(sim.vehicle_count()) + " vehicles)";
  return std::nullopt;
}

}  // namespace uavsim::server::api
