// MISSION_ITEM_INT -> MISSION_ITEM: the legacy message a MISSION_REQUEST (not _INT) is answered with, by the
// server's vehicles and by the client when it uploads a mission.
#pragma once

#include "uavsim/common/mavlink/generated/messages.hpp"

namespace uavsim::common::mavlink {

// Latitude and longitude as float degrees (x, y = 1e7 degrees in the _INT message); the _INT frames become
// their float twins (GLOBAL_INT -> GLOBAL, GLOBAL_RELATIVE_ALT_INT -> GLOBAL_RELATIVE_ALT), any other frame
// is kept. Every other field is copied. Pure.
msg::MissionItem legacy_mission_item(const msg::MissionItemInt& m);

}  // namespace uavsim::common::mavlink
