// Typed, non-throwing access to the fields of an API request (a JSON object), and the checks every
// request line passes before an op sees it: nesting depth, a scalar id, fields of the declared type.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

#include "uavsim/common/api_error.hpp"

namespace uavsim::server::api {

// Deeper JSON is refused at parse time: nlohmann copies, prints and compares values recursively, so a
// request nested 70k deep would overflow the stack of whichever thread touched it.
inline constexpr int kMaxNestingDepth = 32;

// The default range of a number field: far beyond any sim time, distance or rate, far below where
// sums and products of two such numbers overflow.
inline constexpr double kMaxMagnitude = 1e15;

enum class FieldType { kNumber, kBoolean, kString, kArray, kObject, kIndexOrName };

// A field an op reads: its name, its JSON type and, for a number, the closed range it must lie in.
// Every number is checked finite (1e999 parses as infinity) and within [min, max] before any handler
// sees it: the one place where a huge, tiny or overflowing number from a client is refused, so no op
// can carry it into a loop, a cast or an allocation. An op may check a narrower range of its own.
struct FieldSpec {
  std::string_view name;
  FieldType type;
  double min = -kMaxMagnitude;
  double max = kMaxMagnitude;
};

// The outcome of parsing one request line.
struct ParsedLine {
  nlohmann::json body;   // the request object, when error_code is empty
  nlohmann::json id;     // the request's id (a scalar or null), for the reply
  std::optional<common::ApiError> error;  // set when the line is refused
  std::string error_message;
};

// Parses a request line: valid JSON (bad_json), at most kMaxNestingDepth deep (bad_request), an object
// (bad_request) whose "id", if any, is a number, string, boolean or null (bad_field: a structured id is
// never echoed) and whose "op" is a string (missing_field). Thread-safe (pure).
ParsedLine parse_request_line(std::string_view line);

// The first field of request that is present with another type than specs gives it (or a number
// outside its range), as a bad_field message naming the field and what it must be; nullopt when every
// present field is well typed and in range.
// Absent fields are the op's business. Thread-safe (pure).
std::optional<std::string> mistyped_field(const nlohmann::json& request, std::span<const FieldSpec> specs);

// The fields the core op groups (clock, events, lockstep, vehicle, camera) read, with their types: a
// request to one of their ops naming one with another type gets bad_field before the op runs (so no op
// half-applies a request). The other groups check their own fields. Thread-safe (constant).
std::span<const FieldSpec> core_op_fields();

// A field of the given type; nullopt when absent or of another type. Thread-safe (pure).
std::optional<double> number_field(const nlohmann::json& request, std::string_view key);
std::optional<bool> bool_field(const nlohmann::json& request, std::string_view key);
std::optional<std::string> string_field(const nlohmann::json& request, std::string_view key);
bool has_field(const nlohmann::json& request, std::string_view key);

}  // namespace uavsim::server::api
