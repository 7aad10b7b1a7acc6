// Plain types shared by the flight-controller emulation and its adapters (sim loop, MAVLink endpoint).
// Frames: the FC works in the local ENU frame of the MuJoCo world (origin = EKF origin, z up) and the
// FLU body frame. MAVLink's conventions (NED, yaw 0 = north clockwise) are converted at the MAVLink
// edge, in server/src/mavlink (with the ENU/NED helpers of common/include/uavsim/common/frames.hpp).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "airframe/truth_state.hpp"

namespace uavsim::server::fc {

// ArduCopter flight modes, with ArduCopter's custom_mode numbers.
enum class Mode : uint32_t {
  kStabilize = 0,
  kAltHold = 2,
  kAuto = 3,
  kGuided = 4,
  kLoiter = 5,
  kRtl = 6,
  kLand = 9,
  kBrake = 17,
};
const char* mode_name(Mode mode);
std::optional<Mode> mode_from_number(uint32_t custom_mode);

// Outcome of a command, mapped 1:1 onto MAV_RESULT by the MAVLink endpoint.
enum class CommandResult {
  kAccepted,
  kDenied,       // e.g. pre-arm check failed, take-off while disarmed   (MAV_RESULT_DENIED)
  kFailed,       // valid but could not be carried out now                 (MAV_RESULT_FAILED)
  kUnsupported,  // unknown mode number, command not implemented          (MAV_RESULT_UNSUPPORTED)
  kInvalid,      // out-of-range or non-finite parameter                   (MAV_RESULT_DENIED too)
};

// Ground truth of a rigid body, the input to the sensor models (defined with the airframe, which
// physics shares).
using airframe::TruthState;

// The estimator's output: what the FC (and telemetry) believes.
struct EstimatedState {
  Eigen::Vector3d position_enu_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d velocity_enu_m_s = Eigen::Vector3d::Zero();
  Eigen::Quaterniond q_enu_body = Eigen::Quaterniond::Identity();
  Eigen::Vector3d rate_body_rad_s = Eigen::Vector3d::Zero();
  Eigen::Vector3d accel_enu_m_s2 = Eigen::Vector3d::Zero();  // without gravity
  double baro_alt_m = 0.0;
  bool gps_ok = false;  // 3D fix and recent samples
  int gps_satellites = 0;
  double gps_hdop = 99.99;
};

// One mission item (AUTO), ArduCopter semantics, in local ENU.
struct MissionItem {
  enum class Kind { kWaypoint, kTakeoff, kLand, kRtl, kLoiterTime, kChangeSpeed, kConditionYaw };
  Kind kind = Kind::kWaypoint;
  Eigen::Vector3d position_enu_m = Eigen::Vector3d::Zero();  // altitude relative to home for kTakeoff
  double param_s_or_m_s = 0.0;  // hold time (kWaypoint, kLoiterTime), speed (kChangeSpeed)
  double yaw_enu_rad = 0.0;     // kConditionYaw: the heading to hold (ENU: 0 = east, counter-clockwise)
  bool position_valid = true;   // false: "use current position" (lat/lon 0 in MAVLink)
};

// A guided-mode setpoint (SET_POSITION_TARGET_*): any combination of position, velocity, acceleration
// and yaw or yaw rate; std::nullopt = ignored by type_mask.
struct GuidedTarget {
  std::optional<Eigen::Vector3d> position_enu_m;
  std::optional<Eigen::Vector3d> velocity_enu_m_s;
  std::optional<Eigen::Vector3d> accel_enu_m_s2;
  std::optional<double> yaw_enu_rad;     // ENU yaw: 0 = east, counter-clockwise positive
  std::optional<double> yaw_rate_rad_s;  // ENU: counter-clockwise positive
};

// A commanded heading: turn to yaw_enu_rad, or by it when relative (counter-clockwise positive), at
// rate_rad_s (0: the ATC_SLEW_YAW default).
struct YawCommand {
  double yaw_enu_rad = 0.0;
  bool relative = false;
  double rate_rad_s = 0.0;
};

// The speed limit a speed change overrides.
enum class SpeedLimit { kHorizontal, kClimb, kDescent };

// SET_ATTITUDE_TARGET in guided mode.
struct AttitudeTarget {
  std::optional<Eigen::Quaterniond> q_enu_body;
  std::optional<Eigen::Vector3d> rate_body_rad_s;
  double thrust = 0.5;  // normalised collective thrust [0, 1]; 0.5 ~ climb rate 0 as in ArduCopter
};

// A pilot's sticks (RC_CHANNELS_OVERRIDE, MANUAL_CONTROL), normalised: roll right, pitch forward (nose
// down) and yaw clockwise (seen from above) positive in [-1, 1]; throttle in [0, 1], 0.5 at mid stick.
struct PilotInput {
  double roll = 0.0;
  double pitch = 0.0;
  double yaw = 0.0;
  double throttle = 0.5;
};

enum class LandedState { kOnGround, kTakeoff, kInAir, kLanding };

// Messages for the GCS (STATUSTEXT), with MAV_SEVERITY numbers.
struct StatusText {
  int severity = 6;  // 6 = INFO, 4 = WARNING, 3 = ERROR, 2 = CRITICAL
  std::string text;
};

}  // namespace uavsim::server::fc
