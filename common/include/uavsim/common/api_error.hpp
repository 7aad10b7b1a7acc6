// The sim API's error codes (docs/protocol.md, "Error codes"): one enum for the server, which answers
// with them, and the client library, which reads them back — one list, so a code the server sends is
// a code the client knows, and the compiler checks every switch over them.
//
// On the wire an error is {"ok": false, "error": {"code": "<code>", "message": "..."}}; the code is
// the enum's snake_case name below. Thread-safe (constants and pure functions).
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string_view>
#include <utility>

namespace uavsim::common {

enum class ApiError : std::uint8_t {
  kBadJson,         // the line is not JSON
  kBadRequest,      // not an object, or nested deeper than the server reads
  kLineTooLong,     // a request line past the server's limit
  kMissingField,    // a required field is absent
  kBadField,        // a field of the wrong type or out of its range; nothing was applied
  kUnknownOp,       // no op of that name on this server
  kUnknownVehicle,  // no vehicle of that index or name
  kNotAvailable,    // this server or world has no such thing (a camera, a relay, a sensor)
  kNotJoined,       // a lockstep op from a connection outside the lockstep
  kBadState,        // not now (e.g. a reset while stepping)
  kBusy,            // another client's step holds the clock
  kInterrupted,     // a step ended early by another clock op
  kUnauthorized,    // the API token is missing or wrong
  kForbidden,       // refused by the server's policy (e.g. a relay target off loopback)
  kOverloaded,      // the connection is closed: too many connections, or its output past the limit
  kFrameTooLarge,   // a radio frame past the channel's largest
  kBadBase64,       // a radio frame's data is not base64
  kQueueFull,       // the sender's radio queue is full
  kIoError,         // the server could not open a socket it was asked for
};

// Every code with its wire name, in the enum's order.
inline constexpr std::array<std::pair<ApiError, std::string_view>, 19> kApiErrorCodes = {{
    {ApiError::kBadJson, "bad_json"},
    {ApiError::kBadRequest, "bad_request"},
    {ApiError::kLineTooLong, "line_too_long"},
    {ApiError::kMissingField, "missing_field"},
    {ApiError::kBadField, "bad_field"},
    {ApiError::kUnknownOp, "unknown_op"},
    {ApiError::kUnknownVehicle, "unknown_vehicle"},
    {ApiError::kNotAvailable, "not_available"},
    {ApiError::kNotJoined, "not_joined"},
    {ApiError::kBadState, "bad_state"},
    {ApiError::kBusy, "busy"},
    {ApiError::kInterrupted, "interrupted"},
    {ApiError::kUnauthorized, "unauthorized"},
    {ApiError::kForbidden, "forbidden"},
    {ApiError::kOverloaded, "overloaded"},
    {ApiError::kFrameTooLarge, "frame_too_large"},
    {ApiError::kBadBase64, "bad_base64"},
    {ApiError::kQueueFull, "queue_full"},
    {ApiError::kIoError, "io_error"},
}};

// The wire name of a code.
constexpr std::string_view api_error_code(ApiError e) {
  return kApiErrorCodes[static_cast<std::size_t>(e)].second;
}

// The code of a wire name; nullopt for a name this library does not know (a newer server's).
constexpr std::optional<ApiError> api_error_from_code(std::string_view code) {
  for (const auto& [e, name] : kApiErrorCodes) {
    if (name == code) return e;
  }
  return std::nullopt;
}

// the table is in the enum's order (api_error_code indexes it)
static_assert([] {
  for (std::size_t i = 0; i < kApiErrorCodes.size(); ++i) {
    if (static_cast<std::size_t>(kApiErrorCodes[i].first) != i) return false;
  }
  return static_cast<std::size_t>(ApiError::kIoError) + 1 == kApiErrorCodes.size();
}());

}  // namespace uavsim::common
