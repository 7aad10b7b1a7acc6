// A request's vehicle field (docs/protocol.md: an index or a name), checked against the simulation:
// shared by the API's op groups so every op names vehicles and reports errors alike.
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>

#include "api/op_table.hpp"
#include "sim/simulation.hpp"

namespace uavsim::server::api {

// The vehicle index value names, or nullopt with reply failed: bad_field for a value that is neither
// an index nor a name, unknown_vehicle for one that names no vehicle. Loop thread only.
inline std::optional<size_t> vehicle_index(const sim::Simulation& sim, const nlohmann::json& value,
                                           OpReply* reply) {
  if (value.is_number_integer() || value.is_number_unsigned()) {
    const int64_t i = value.get<int64_t>();
    if (i >= 0 && static_cast<size_t>(i) < sim.vehicle_count()) return static_cast<size_t>(i);
  } else if (value.is_string()) {
    for (size_t i = 0; i < sim.vehicle_count(); ++i) {
      if (sim.vehicle_name(i) == value.get<std::string>()) return i;
    }
  } else {
    reply->fail(ApiError::kBadField, "a vehicle is an index or a name");
    return std::nullopt;
  }
  reply->fail(ApiError::kUnknownVehicle,
              "no vehicle " + value.dump() + " (" + std::to_string(sim.vehicle_count()) + " vehicles)");
  return std::nullopt;
}

// The vehicle of the request's field key (default "vehicle"), which is required: missing_field (the
// message says what the vehicle is for, e.g. "the sender") when absent, else as vehicle_index.
inline std::optional<size_t> required_vehicle(const sim::Simulation& sim, const nlohmann::json& request,
                                              OpReply* reply, std::string_view role = "index or name",
                                              const char* key = "vehicle") {
  const auto it = request.find(key);
  if (it == request.end()) {
    reply->fail(ApiError::kMissingField, "\"" + std::string(key) + "\" (" + std::string(role) + ") is required");
    return std::nullopt;
  }
  return vehicle_index(sim, *it, reply);
}

// The vehicle of the request's "vehicle" field when present (nullopt without a failure when absent).
// Loop thread only.
inline std::optional<size_t> optional_vehicle(const sim::Simulation& sim, const nlohmann::json& request,
                                              OpReply* reply) {
  const auto it = request.find("vehicle");
  return it == request.end() ? std::nullopt : vehicle_index(sim, *it, reply);
}

}  // namespace uavsim::server::api
