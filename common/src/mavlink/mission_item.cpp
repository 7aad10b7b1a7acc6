#include "uavsim/common/mavlink/mission_item.hpp"

#include "uavsim/common/mavlink/generated/enums.hpp"

namespace uavsim::common::mavlink {

msg::MissionItem legacy_mission_item(const msg::MissionItemInt& m) {
  const auto frame = [](MavFrame f) { return static_cast<std::uint8_t>(to_underlying(f)); };
  msg::MissionItem legacy;
  legacy.param1 = m.param1;
  legacy.param2 = m.param2;
  legacy.param3 = m.param3;
  legacy.param4 = m.param4;
  legacy.x = static_cast<float>(m.x / 1e7);
  legacy.y = static_cast<float>(m.y / 1e7);
  legacy.z = m.z;
  legacy.seq = m.seq;
  legacy.command = m.command;
  legacy.target_system = m.target_system;
  legacy.target_component = m.target_component;
  legacy.frame = m.frame;
  if (m.frame == frame(MavFrame::GlobalInt)) legacy.frame = frame(MavFrame::Global);
  if (m.frame == frame(MavFrame::GlobalRelativeAltInt)) legacy.frame = frame(MavFrame::GlobalRelativeAlt);
  legacy.current = m.current;
  legacy.autocontinue = m.autocontinue;
  legacy.mission_type = m.mission_type;
  return legacy;
}

}  // namespace uavsim::common::mavlink
