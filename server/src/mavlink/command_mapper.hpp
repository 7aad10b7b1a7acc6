// The pure half of MAVLink commands: COMMAND_LONG, COMMAND_INT and SET_MODE read into a typed
// request for the flight controller, the gimbal or the link, with every number range-checked on the
// way (ArduCopter's semantics, docs/mavlink.md §4). No sockets and no state: the endpoint's
// VehicleLink maps a command here, carries the request out and acks with the result these functions
// give. MAVLink's conventions (headings "0 = north, clockwise", degrees, SPEED_TYPE numbers,
// lat/lon degE7) end here: the requests for the flight controller are in its own terms (ENU yaw,
// radians, fc::SpeedLimit).
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <variant>

#include "fc/flight_controller.hpp"
#include "mavlink/gimbal_state.hpp"
#include "uavsim/common/geodesy.hpp"
#include "uavsim/common/mavlink/generated/messages.hpp"

namespace uavsim::server::mavlink {

// std::visit over lambdas: Overloaded{[](const A&) {...}, [](const B&) {...}}
template <class... F>
struct Overloaded : F... {
  using F::operator()...;
};
// (C++20 deduces this for aggregates, but clang before 17 does not: the sanitizer build uses clang)
template <class... F>
Overloaded(F...) -> Overloaded<F...>;

// One command as COMMAND_LONG, COMMAND_INT or SET_MODE carries it.
struct CommandArgs {
  std::uint16_t command = 0;
  std::array<double, 7> p{};  // param1..7; COMMAND_INT: x, y as degrees in p[4], p[5]
  bool is_int = false;
  int frame = 3;              // COMMAND_INT frame; COMMAND_LONG: GLOBAL_RELATIVE_ALT
  std::int32_t x = 0, y = 0;  // COMMAND_INT lat/lon degE7
};

namespace cmd {
// --- for the flight controller ---
struct Arm {
  bool force = false;
};
struct Disarm {
  bool force = false;
};
struct SetMode {
  fc::Mode mode = fc::Mode::kStabilize;
};
struct Takeoff {
  double altitude_above_home_m = 0.0;
};
struct Land {};
struct Rtl {};
struct Yaw {
  fc::YawCommand yaw;
};
struct ChangeSpeed {
  fc::SpeedLimit limit = fc::SpeedLimit::kHorizontal;
  double speed_m_s = 0.0;
};
struct MissionStart {
  int first = 0, last = 0;
};
struct SetMissionCurrent {
  int seq = 0;
};
// DO_REPOSITION: GUIDED to a lat/lon (none: stay) at an altitude (none: keep), AMSL or above home
struct Reposition {
  std::optional<::uavsim::common::Geodetic> lat_lon;  // alt_m unused
  std::optional<double> alt_m;
  bool amsl = false;
};
// --- for the camera gimbal ---
struct MountControl {
  std::optional<double> pitch_deg, roll_deg, yaw_deg;
  std::uint8_t mount_mode = 0;  // 0 keeps the mode
};
struct GimbalPitchYaw {
  std::optional<double> pitch_deg, yaw_deg;
  double pitch_rate_deg_s = 0.0, yaw_rate_deg_s = 0.0;
  bool yaw_lock = false;  // yaw is a heading (earth frame)
};
// --- answered by the link ---
struct SendHome {};
struct SendAutopilotVersion {};
struct RequestMessage {
  std::uint32_t msgid = 0;
};
struct SetMessageInterval {
  std::uint32_t msgid = 0;
  double interval_us = 0.0;  // 0: the default, < 0: stop
};
struct GetMessageInterval {
  std::uint32_t msgid = 0;
};
struct SendBanner {};
}  // namespace cmd

using FcRequest =
    std::variant<cmd::Arm, cmd::Disarm, cmd::SetMode, cmd::Takeoff, cmd::Land, cmd::Rtl, cmd::Yaw,
                 cmd::ChangeSpeed, cmd::MissionStart, cmd::SetMissionCurrent, cmd::Reposition>;
using GimbalRequest = std::variant<cmd::MountControl, cmd::GimbalPitchYaw>;
using LinkRequest = std::variant<cmd::SendHome, cmd::SendAutopilotVersion, cmd::RequestMessage,
                                 cmd::SetMessageInterval, cmd::GetMessageInterval, cmd::SendBanner>;
using CommandRequest = std::variant<FcRequest, GimbalRequest, LinkRequest>;

// A command read: the request to carry out, or, when there is none, the MAV_RESULT to ack at once
// (a refused number, an unknown command, a request that needs nothing done).
struct MappedCommand {
  std::optional<CommandRequest> request;
  std::uint8_t result = 0;
};

// The command a COMMAND_LONG, COMMAND_INT or SET_MODE carries (SET_MODE as MAV_CMD_DO_SET_MODE).
// Pure.
CommandArgs command_args(const ::uavsim::common::mavlink::msg::CommandLong& m);
CommandArgs command_args(const ::uavsim::common::mavlink::msg::CommandInt& m);
CommandArgs command_args(const ::uavsim::common::mavlink::msg::SetMode& m);

// Reads one command. Thread-safe (pure).
MappedCommand map_command(const CommandArgs& c);

// The MAV_RESULT for the flight controller's answer to a request: ArduPilot answers a refused arm,
// disarm or take-off with FAILED, anything else 1:1 (kInvalid as DENIED). Thread-safe (pure).
std::uint8_t ack_result(const FcRequest& request, fc::CommandResult result);

// Carries a request out on fc and returns its MAV_RESULT; origin places DO_REPOSITION's lat/lon.
// Loop thread only (fc's contract).
std::uint8_t execute(const FcRequest& request, fc::FlightController& fc,
                     const ::uavsim::common::GeodeticOrigin& origin);

// Points the gimbal as a request asks, stamped now_s. Thread-safe (pure on gimbal).
void apply(const GimbalRequest& request, GimbalState& gimbal, double now_s);

}  // namespace uavsim::server::mavlink
