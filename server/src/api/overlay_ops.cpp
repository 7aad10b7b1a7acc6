#include "api/overlay_ops.hpp"

#include <algorithm>
#include <optional>

#include "api/request_fields.hpp"
#include "api/vehicle_arg.hpp"

namespace uavsim::server::api {

namespace {

// text for a video frame: printable ASCII only (the overlay's font has nothing else), bounded
bool overlay_text(const std::string& s, size_t max_bytes) {
  return s.size() <= max_bytes &&
         std::all_of(s.begin(), s.end(), [](char c) { return c >= 0x20 && c < 0x7f; });
}

// the text field both ops carry: printable ASCII of at most kMaxOverlayTextBytes
std::optional<std::string> overlay_text_field(const nlohmann::json& request, OpReply* reply) {
  const std::optional<std::string> text = string_field(request, "text");
  if (!text) {
    reply->fail(ApiError::kMissingField, "\"text\" (a string) is required");
  } else if (!overlay_text(*text, kMaxOverlayTextBytes)) {
    reply->fail(ApiError::kBadField, "\"text\" must be printable ASCII of at most " +
                                         std::to_string(kMaxOverlayTextBytes) + " bytes");
    return std::nullopt;
  }
  return text;
}

}  // namespace

void OverlayOps::register_ops(OpTable& table) {
  static constexpr FieldSpec kCounterFields[] = {{"name", FieldType::kString},
                                                 {"text", FieldType::kString}};
  static constexpr FieldSpec kNoteFields[] = {{"text", FieldType::kString},
                                              {"vehicle", FieldType::kIndexOrName}};
  const OpRegistrar<OverlayOps> add(table, this, "overlay");
  add("overlay_counter", &OverlayOps::counter, kCounterFields);
  add("overlay_note", &OverlayOps::note, kNoteFields);
}

std::vector<std::string> OverlayOps::counters() const {
  std::vector<std::string> out;
  for (const auto& [name, text] : counters_) out.push_back(text);
  return out;
}

void OverlayOps::counter(const Json& request, OpReply* reply) {
  const std::optional<std::string> text = overlay_text_field(request, reply);
  if (!text) return;
  const std::optional<std::string> name = string_field(request, "name");
  if (!name || name->empty() || !overlay_text(*name, kMaxOverlayNameBytes)) {
    return reply->fail(ApiError::kBadField, "\"name\" must be printable ASCII of 1 to " +
                                                std::to_string(kMaxOverlayNameBytes) + " bytes");
  }
  if (text->empty()) {
    counters_.erase(*name);
  } else if (counters_.count(*name) == 0 && counters_.size() >= kMaxOverlayCounters) {
    return reply->fail(ApiError::kBadField,
                       "at most " + std::to_string(kMaxOverlayCounters) + " counters");
  } else {
    counters_[*name] = *text;
  }
  reply->result = {{"counters", counters_.size()}};
}

void OverlayOps::note(const Json& request, OpReply* reply) {
  const std::optional<std::string> text = overlay_text_field(request, reply);
  if (!text) return;
  int vehicle = -1;
  if (has_field(request, "vehicle")) {
    const auto v = optional_vehicle(sim_, request, reply);
    if (!v) return;
    vehicle = static_cast<int>(*v);
  }
  notes_.push_back({sim_.time_s(), vehicle, *text});
  if (notes_.size() > kMaxOverlayNotes) notes_.pop_front();
  reply->result = {{"time_s", sim_.time_s()}};
}

}  // namespace uavsim::server::api
