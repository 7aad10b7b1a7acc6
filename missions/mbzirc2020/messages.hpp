// The mission's ground-station topics (seed 6.3 protocol, seed 7.2 topics) and their payloads.
// Topic ids with the high bit set are latest-only (a newer message replaces an unacknowledged older
// one).
//   STATE     GCS -> UAV, queued: start / land / take over the other side / re-task (seed:
//             "start, monitor and land")
//   AIRSPACE  both ways, latest-only: a UAV's request (its position and the balloon it will
//             pierce), echoed unchanged by the GCS when granted; all NaN releases (seed 7.2, note
//             40)
//   STATUS    UAV -> GCS, latest-only: FSM state, flags, position, balloons it believes it popped
//   POPPED    UAV -> GCS, queued: where a balloon was pierced
// Payloads are big-endian (doubles as IEEE-754 bit patterns), so any ground station can decode
// them.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <vector>

namespace uavsim::missions::mbzirc2020 {

inline constexpr uint16_t kTopicState = 0x0001;
inline constexpr uint16_t kTopicAirspace = 0x8002;
inline constexpr uint16_t kTopicStatus = 0x8003;
inline constexpr uint16_t kTopicPopped = 0x0004;

// kReTask: your own scans are done and balloons remain: scan the other half too (vehicle_fsm.hpp)
enum class GcsCommand : uint8_t { kStart = 1, kLand = 2, kTakeOver = 3, kReTask = 4 };

// An airspace request: the requester's position and the point it will fly to (x, y in the field
// frame). Unset (std::nullopt) is the release, sent as NaN on the wire as the seed does.
struct AirspaceArea {
  Eigen::Vector2d from_enu_m = Eigen::Vector2d::Zero();
  Eigen::Vector2d to_enu_m = Eigen::Vector2d::Zero();
  bool operator==(const AirspaceArea& o) const {
    return from_enu_m == o.from_enu_m && to_enu_m == o.to_enu_m;
  }
};

struct UavStatus {
  uint8_t state = 0;    // VehicleState
  bool ready = false;   // on the ground, ready to arm
  bool failed = false;  // lost its motors / disarmed in the air: out of the mission
  bool landed = false;  // mission over, on the ground
  Eigen::Vector3d position_enu_m = Eigen::Vector3d::Zero();
  uint8_t popped = 0;
};

std::vector<uint8_t> encode_command(GcsCommand c);
std::optional<GcsCommand> decode_command(const std::vector<uint8_t>& p);
std::vector<uint8_t> encode_airspace(const std::optional<AirspaceArea>& a);
// nullopt: malformed; a nullopt inside: the NaN release.
std::optional<std::optional<AirspaceArea>> decode_airspace(const std::vector<uint8_t>& p);
std::vector<uint8_t> encode_status(const UavStatus& s);
std::optional<UavStatus> decode_status(const std::vector<uint8_t>& p);
std::vector<uint8_t> encode_point(const Eigen::Vector2d& p_enu_m);
std::optional<Eigen::Vector2d> decode_point(const std::vector<uint8_t>& p);

}  // namespace uavsim::missions::mbzirc2020
