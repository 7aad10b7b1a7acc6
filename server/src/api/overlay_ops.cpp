#include "api/overlay_ops.hpp"

#include <algorithm>
#include <functional>

#include "api/request_fields.hpp"
#include "api/vehicle_arg.hpp"

namespace uavsim::server::api {

namespace {

// text for a video frame: printable ASCII only (the overlay's font has nothing else), bounded
bool overlay_text(const std::string& s, size_t max_bytes) {
  return s.size() <= max_bytes &&
         std::all_of(s.begin(), s.end(), [](char c) { return c >= 0x20 && c < 0x7f; });
}

}  // namespace

void OverlayOps::register_ops(OpTable& table) {
  static constexpr std::string_view kOps[] = {"overlay_counter", "overlay_note"};
  table.add_named("overlay", kOps, std::bind_front(&OverlayOps::handle, this));
}

std::vector<std::string> OverlayOps::counters() const {
  std::vector<std::string> out;
  for (const auto& [name, text] : counters_) out.push_back(text);
  return out;
}

bool OverlayOps::handle(uint64_t, const std::string& op, const Json& request, Json* result,
                        std::string* code, std::string* message) {
  const auto fail = [&](const std::string& c, const std::string& m) {
    *code = c;
    *message = m;
    return false;
  };
  const std::optional<std::string> text = string_field(request, "text");
  if (!text) return fail("missing_field", "\"text\" (a string) is required");
  if (!overlay_text(*text, kMaxOverlayTextBytes)) {
    return fail("bad_field", "\"text\" must be printable ASCII of at most " +
                                 std::to_string(kMaxOverlayTextBytes) + " bytes");
  }
  if (op == "overlay_counter") {
    const std::optional<std::string> name = string_field(request, "name");
    if (!name || name->empty() || !overlay_text(*name, kMaxOverlayNameBytes)) {
      return fail("bad_field", "\"name\" must be printable ASCII of 1 to " +
                                   std::to_string(kMaxOverlayNameBytes) + " bytes");
    }
    if (text->empty()) {
      counters_.erase(*name);
    } else if (counters_.count(*name) == 0 && counters_.size() >= kMaxOverlayCounters) {
      return fail("bad_field", "at most " + std::to_string(kMaxOverlayCounters) + " counters");
    } else {
      counters_[*name] = *text;
    }
    *result = {{"counters", counters_.size()}};
    return true;
  }
  // overlay_note
  int vehicle = -1;
  if (has_field(request, "vehicle")) {
    const auto v = vehicle_index(sim_, request["vehicle"], code, message);
    if (!v) return false;
    vehicle = static_cast<int>(*v);
  }
  notes_.push_back({sim_.time_s(), vehicle, *text});
  if (notes_.size() > kMaxOverlayNotes) notes_.pop_front();
  *result = {{"time_s", sim_.time_s()}};
  return true;
}

}  // namespace uavsim::server::api
