// MAV_CMD_COMPONENT_ARM_DISARM's param2 values that skip the safety checks. MAVLink's common.xml
// names 21196 for both directions: an arm past the pre-arm checks, a disarm in flight. ArduCopter
// forces an arm with 2989 (its magic_force_arm_value) and a disarm with 21196 only. The client
// sends ArduCopter's values; the server's command mapper accepts either for an arm, as both ground
// stations do, and only 21196 for a disarm.
#pragma once

namespace uavsim::common::mavlink {

inline constexpr float kForceArmMagic = 2989.0f;
inline constexpr float kForceArmDisarmMagic = 21196.0f;

}  // namespace uavsim::common::mavlink
