#include "uavsim/common/mavlink/mission_item.hpp"

#include <cmath>
#include <cstdint>

#include "uavsim/common/mavlink/generated/enums.hpp"

namespace uavsim::common::mavlink {

namespace {

constexpr std::uint8_t frame_id(MavFrame f) { return static_cast<std::uint8_t>(to_underlying(f)); }

// |deg| <= limit, false for NaN
bool within(double deg, double limit) { return std::fabs(deg) <= limit; }

// Every field the two messages share and carry alike (all but x, y and frame).
template <class To, class From>
void copy_common_fields(const From& from, To& to) {
  to.param1 = from.param1;
  to.param2 = from.param2;
  to.param3 = from.param3;
  to.param4 = from.param4;
  to.z = from.z;
  to.seq = from.seq;
  to.command = from.command;
  to.target_system = from.target_system;
  to.target_component = from.target_component;
  to.current = from.current;
  to.autocontinue = from.autocontinue;
  to.mission_type = from.mission_type;
}

}  // namespace

msg::MissionItem legacy_mission_item(const msg::MissionItemInt& m) {
  msg::MissionItem legacy;
  copy_common_fields(m, legacy);
  legacy.x = static_cast<float>(m.x / 1e7);
  legacy.y = static_cast<float>(m.y / 1e7);
  legacy.frame = m.frame;
  if (m.frame == frame_id(MavFrame::GlobalInt)) legacy.frame = frame_id(MavFrame::Global);
  if (m.frame == frame_id(MavFrame::GlobalRelativeAltInt))
    legacy.frame = frame_id(MavFrame::GlobalRelativeAlt);
  return legacy;
}

std::optional<msg::MissionItemInt> mission_item_int_from_legacy(const msg::MissionItem& m) {
  if (!within(m.x, 90.0) || !within(m.y, 180.0)) return std::nullopt;
  msg::MissionItemInt i;
  copy_common_fields(m, i);
  i.x = static_cast<std::int32_t>(std::llround(static_cast<double>(m.x) * 1e7));
  i.y = static_cast<std::int32_t>(std::llround(static_cast<double>(m.y) * 1e7));
  i.frame = m.frame;
  if (m.frame == frame_id(MavFrame::Global)) i.frame = frame_id(MavFrame::GlobalInt);
  if (m.frame == frame_id(MavFrame::GlobalRelativeAlt))
    i.frame = frame_id(MavFrame::GlobalRelativeAltInt);
  return i;
}

}  // namespace uavsim::common::mavlink
