#include "api/request_fields.hpp"

#include <cmath>
#include <sstream>

namespace uavsim::server::api {

using Json = nlohmann::json;

namespace {

bool has_type(const Json& v, FieldType type) {
  switch (type) {
    case FieldType::kNumber: return v.is_number();
    case FieldType::kBoolean: return v.is_boolean();
    case FieldType::kString: return v.is_string();
    case FieldType::kArray: return v.is_array();
    case FieldType::kObject: return v.is_object();
    case FieldType::kIndexOrName: return v.is_number_integer() || v.is_string();
  }
  return false;
}

const char* type_name(FieldType type) {
  switch (type) {
    case FieldType::kNumber: return "a number";
    case FieldType::kBoolean: return "true or false";
    case FieldType::kString: return "a string";
    case FieldType::kArray: return "an array";
    case FieldType::kObject: return "an object";
    case FieldType::kIndexOrName: return "an index or a name";
  }
  return "?";
}

// 2^64 as a double: seeds and sequence numbers are below it (the ops check the exact integer)
constexpr double kTwoTo64 = 18446744073709551616.0;

constexpr FieldSpec kCoreOpFields[] = {
    {"steps", FieldType::kNumber, 1, 1e9},
    {"duration_s", FieldType::kNumber, 0, 1e9},
    {"rate", FieldType::kNumber, 0, 1e6},
    {"seed", FieldType::kNumber, 0, kTwoTo64},
    {"from_seq", FieldType::kNumber, 0, kTwoTo64},
    {"vehicle", FieldType::kIndexOrName},
    {"reason", FieldType::kString},
    {"rotor", FieldType::kNumber, 0, 1024},
    {"failed", FieldType::kBoolean},
    {"offset_enu_m", FieldType::kArray},
    {"denied", FieldType::kBoolean},
    {"down", FieldType::kBoolean},
    {"gimbal", FieldType::kString},
    {"mode", FieldType::kString},
    {"pitch_deg", FieldType::kNumber, -360, 360},
    {"yaw_deg", FieldType::kNumber, -360, 360},
    {"period_s", FieldType::kNumber, 0, 3600},
    {"timeout_s", FieldType::kNumber, 0, 1e6},
    {"tick", FieldType::kNumber, 0, kTwoTo64},
    {"busy_until", FieldType::kNumber},
    {"mavlink_seq", FieldType::kObject},
    {"quiet", FieldType::kBoolean},
    {"speed_m_s", FieldType::kNumber, 0, 1000},
    {"from_deg", FieldType::kNumber, -360, 360},
    {"turbulence_sd_m_s", FieldType::kNumber, 0, 1000},
    {"gust_m_s", FieldType::kNumber, 0, 1000},
    {"gust_duration_s", FieldType::kNumber, 0, 86400},
    {"time_s", FieldType::kNumber},
    {"lockstep_empty", FieldType::kBoolean},
    {"fps", FieldType::kNumber, 0, 1e6},
    {"quality", FieldType::kNumber, 1, 100},
    {"ring_bytes", FieldType::kNumber, 65536, 268435456},
};

// "[0, 3600]" with the bounds as a person writes them
std::string range_text(double lo, double hi) {
  std::ostringstream s;
  s << "[" << lo << ", " << hi << "]";
  return s.str();
}

}  // namespace

std::span<const FieldSpec> core_op_fields() { return kCoreOpFields; }

ParsedLine parse_request_line(std::string_view line) {
  ParsedLine out;
  out.id = nullptr;
  auto fail = [&out](common::ApiError code, std::string message) {
    out.body = Json();
    out.error = code;
    out.error_message = std::move(message);
    return out;
  };
  // the parser is iterative; the callback stops it from keeping anything below the depth limit, so a
  // deep line costs a flag, not a deep value
  bool too_deep = false;
  const Json::parser_callback_t limit_depth = [&too_deep](int depth, Json::parse_event_t, Json&) {
    if (depth > kMaxNestingDepth) too_deep = true;
    return !too_deep;
  };
  Json body = Json::parse(line.begin(), line.end(), limit_depth, false);
  if (too_deep) {
    return fail(common::ApiError::kBadRequest, "requests nest at most " + std::to_string(kMaxNestingDepth) + " levels deep");
  }
  if (body.is_discarded()) return fail(common::ApiError::kBadJson, "the line is not valid JSON");
  if (!body.is_object()) return fail(common::ApiError::kBadRequest, "a request is a JSON object");
  if (auto it = body.find("id"); it != body.end()) {
    if (it->is_structured() || it->is_binary()) {
      return fail(common::ApiError::kBadField, "\"id\" must be a number, a string, a boolean or null");
    }
    out.id = *it;
  }
  if (!string_field(body, "op")) {
    Json id = out.id;
    fail(common::ApiError::kMissingField, "a request needs \"op\" (a string)");
    out.id = std::move(id);
    return out;
  }
  out.body = std::move(body);
  return out;
}

std::optional<std::string> mistyped_field(const Json& request, std::span<const FieldSpec> specs) {
  for (const FieldSpec& spec : specs) {
    auto it = request.find(spec.name);
    if (it == request.end()) continue;
    if (!has_type(*it, spec.type)) return "\"" + std::string(spec.name) + "\" must be " + type_name(spec.type);
    if (spec.type != FieldType::kNumber) continue;
    const double v = it->get<double>();
    if (!std::isfinite(v) || v < spec.min || v > spec.max) {
      return "\"" + std::string(spec.name) + "\" must be a number in " + range_text(spec.min, spec.max);
    }
  }
  return std::nullopt;
}

std::optional<double> number_field(const Json& request, std::string_view key) {
  auto it = request.find(key);
  if (it == request.end() || !it->is_number()) return std::nullopt;
  return it->get<double>();
}

std::optional<bool> bool_field(const Json& request, std::string_view key) {
  auto it = request.find(key);
  if (it == request.end() || !it->is_boolean()) return std::nullopt;
  return it->get<bool>();
}

std::optional<std::string> string_field(const Json& request, std::string_view key) {
  auto it = request.find(key);
  if (it == request.end() || !it->is_string()) return std::nullopt;
  return it->get<std::string>();
}

bool has_field(const Json& request, std::string_view key) { return request.find(key) != request.end(); }

}  // namespace uavsim::server::api
