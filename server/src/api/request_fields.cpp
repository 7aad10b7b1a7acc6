#include "api/request_fields.hpp"

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

constexpr FieldSpec kCoreOpFields[] = {
    {"steps", FieldType::kNumber},       {"duration_s", FieldType::kNumber},
    {"rate", FieldType::kNumber},        {"seed", FieldType::kNumber},
    {"from_seq", FieldType::kNumber},    {"vehicle", FieldType::kIndexOrName},
    {"reason", FieldType::kString},      {"rotor", FieldType::kNumber},
    {"failed", FieldType::kBoolean},     {"offset_enu_m", FieldType::kArray},
    {"denied", FieldType::kBoolean},     {"down", FieldType::kBoolean},
    {"gimbal", FieldType::kString},      {"mode", FieldType::kString},
    {"pitch_deg", FieldType::kNumber},   {"yaw_deg", FieldType::kNumber},
    {"period_s", FieldType::kNumber},    {"timeout_s", FieldType::kNumber},
    {"tick", FieldType::kNumber},        {"busy_until", FieldType::kNumber},
    {"mavlink_seq", FieldType::kObject},
    {"speed_m_s", FieldType::kNumber},   {"from_deg", FieldType::kNumber},
    {"turbulence_sd_m_s", FieldType::kNumber}, {"gust_m_s", FieldType::kNumber},
    {"gust_duration_s", FieldType::kNumber},
    {"time_s", FieldType::kNumber},      {"lockstep_empty", FieldType::kBoolean},
};

}  // namespace

std::span<const FieldSpec> core_op_fields() { return kCoreOpFields; }

ParsedLine parse_request_line(std::string_view line) {
  ParsedLine out;
  out.id = nullptr;
  auto fail = [&out](const char* code, std::string message) {
    out.body = Json();
    out.error_code = code;
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
    return fail("bad_request", "requests nest at most " + std::to_string(kMaxNestingDepth) + " levels deep");
  }
  if (body.is_discarded()) return fail("bad_json", "the line is not valid JSON");
  if (!body.is_object()) return fail("bad_request", "a request is a JSON object");
  if (auto it = body.find("id"); it != body.end()) {
    if (it->is_structured() || it->is_binary()) {
      return fail("bad_field", "\"id\" must be a number, a string, a boolean or null");
    }
    out.id = *it;
  }
  if (!string_field(body, "op")) {
    Json id = out.id;
    fail("missing_field", "a request needs \"op\" (a string)");
    out.id = std::move(id);
    return out;
  }
  out.body = std::move(body);
  return out;
}

std::optional<std::string> mistyped_field(const Json& request, std::span<const FieldSpec> specs) {
  for (const FieldSpec& spec : specs) {
    auto it = request.find(spec.name);
    if (it == request.end() || has_type(*it, spec.type)) continue;
    return "\"" + std::string(spec.name) + "\" must be " + type_name(spec.type);
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
