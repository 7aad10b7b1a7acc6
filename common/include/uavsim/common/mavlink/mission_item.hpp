// MISSION_ITEM_INT <-> MISSION_ITEM: the legacy float message and its _INT twin. The server's
// vehicles answer a MISSION_REQUEST (not _INT) with the legacy form and take a legacy MISSION_ITEM
// by converting it; the client uploads a mission in the legacy form to a peer that asks for it. One
// pair, so both sides agree on the scaling and the frames.
#pragma once

#include <optional>

#include "uavsim/common/mavlink/generated/messages.hpp"

namespace uavsim::common::mavlink {

// Latitude and longitude as float degrees (x, y = 1e7 degrees in the _INT message); the _INT frames
// become their float twins (GLOBAL_INT -> GLOBAL, GLOBAL_RELATIVE_ALT_INT -> GLOBAL_RELATIVE_ALT),
// any other frame is kept. Every other field is copied. Pure.
msg::MissionItem legacy_mission_item(const msg::MissionItemInt& m);

// The inverse: x, y (degrees) rounded to 1e-7 degrees (about 1 cm), GLOBAL -> GLOBAL_INT and
// GLOBAL_RELATIVE_ALT -> GLOBAL_RELATIVE_ALT_INT, any other frame kept, every other field copied.
// nullopt when x is not a latitude in [-90, 90] or y not a longitude in [-180, 180] (NaN included):
// the 1e7 scaling of anything larger would overflow the int32 fields. Pure.
std::optional<msg::MissionItemInt> mission_item_int_from_legacy(const msg::MissionItem& m);

}  // namespace uavsim::common::mavlink
