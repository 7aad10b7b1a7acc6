// Vehicle: a proxy for one ArduCopter-compatible vehicle over MAVLink TCP (a real drone's companion link,
// ArduPilot SITL, or uavsim-server's endpoint, which behaves like SITL). Mission programs use this and
// nothing simulator-specific, so they run unchanged against a real drone.
//
// It keeps a telemetry cache, sends GCS heartbeats at 1 Hz (so the vehicle's GCS failsafe, FS_GCS_ENABLE,
// takes over if this process dies: seed 6.1 fault isolation), and offers commands whose outcome is a
// Result: the vehicle's refusal (with the MAV_RESULT), a timeout, or a lost link — never silent.
//
// Loop-thread only (see EventLoop): blocking calls (connect, wait_ready, arm, ...) keep the loop running
// while they wait, so timers and other vehicles carry on; under lockstep every timeout is in sim time.
#pragma once

#include <array>
#include <cstdint>
#include <limits>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "uavsim/client/event_loop.hpp"
#include "uavsim/client/geodesy.hpp"
#include "uavsim/client/result.hpp"

namespace uavsim::client {

// ArduCopter flight modes (custom_mode numbers).
enum class FlightMode : std::uint32_t {
  kStabilize = 0, kAcro = 1, kAltHold = 2, kAuto = 3, kGuided = 4, kLoiter = 5, kRtl = 6, kCircle = 7,
  kLand = 9, kDrift = 11, kSport = 13, kFlip = 14, kAutotune = 15, kPosHold = 16, kBrake = 17, kThrow = 18,
  kAvoidAdsb = 19, kGuidedNoGps = 20, kSmartRtl = 21, kFlowHold = 22, kFollow = 23, kZigZag = 24,
  kSystemId = 25, kAutorotate = 26, kAutoRtl = 27, kTurtle = 28,
};
const char* mode_name(FlightMode m);  // "GUIDED", ...; "UNKNOWN" for other numbers

enum class LandedState { kUnknown = 0, kOnGround = 1, kInAir = 2, kTakeoff = 3, kLanding = 4 };

struct Telemetry {
  // link
  bool heartbeat_seen = false;
  double last_heartbeat_time = -1.0;  // loop clock
  std::uint8_t sysid = 0;             // the vehicle's MAVLink system id
  // state (HEARTBEAT, EXTENDED_SYS_STATE, SYS_STATUS)
  FlightMode mode = FlightMode::kStabilize;
  std::uint32_t custom_mode = 0;
  bool armed = false;
  std::uint8_t system_status = 0;     // MAV_STATE
  LandedState landed = LandedState::kUnknown;
  std::uint32_t sensors_health = 0;   // SYS_STATUS onboard_control_sensors_health
  bool prearm_ok = false;             // SYS_STATUS health bit MAV_SYS_STATUS_PREARM_CHECK
  std::uint16_t ekf_flags = 0;        // EKF_STATUS_REPORT flags
  bool ekf_ok = false;                // EKF_PRED_POS_HORIZ_ABS (or no EKF report and pre-arm ok)
  // pose: vehicle time (time_boot_ms) of the last position, local frame relative to the EKF origin
  double vehicle_time_s = 0.0;
  bool has_local_position = false;
  Eigen::Vector3d position_ned_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d velocity_ned_m_s = Eigen::Vector3d::Zero();
  Eigen::Vector3d position_enu_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d velocity_enu_m_s = Eigen::Vector3d::Zero();
  bool has_global_position = false;
  Geodetic position;                  // GLOBAL_POSITION_INT (altitude AMSL)
  double relative_alt_m = 0.0;        // above home
  // attitude (ATTITUDE, NED: yaw clockwise from north)
  bool has_attitude = false;
  double roll_rad = 0.0, pitch_rad = 0.0, yaw_rad = 0.0;
  Eigen::Vector3d body_rates_rad_s = Eigen::Vector3d::Zero();
  double heading_deg = 0.0;           // 0..360 clockwise from north
  // battery (SYS_STATUS / BATTERY_STATUS)
  double battery_voltage_v = 0.0;
  double battery_current_a = 0.0;
  int battery_remaining_pct = -1;
  double battery_consumed_mah = 0.0;
  // GPS (GPS_RAW_INT)
  int gps_fix_type = 0;               // GPS_FIX_TYPE: 3 = 3D fix
  int gps_satellites = 0;
  double gps_hdop = 0.0;
  Geodetic gps_position;
  // home (HOME_POSITION) and EKF origin (GPS_GLOBAL_ORIGIN)
  bool home_set = false;
  Geodetic home;
  Eigen::Vector3d home_ned_m = Eigen::Vector3d::Zero();
  bool origin_set = false;
  GeodeticOrigin origin{0.0, 0.0, 0.0, 0.0};  // all zero until origin_set, not the default home
  // gimbal (MOUNT_STATUS), degrees
  bool has_gimbal = false;
  double gimbal_pitch_deg = 0.0, gimbal_roll_deg = 0.0, gimbal_yaw_deg = 0.0;
  // the camera's attitude as its gimbal device measures it (GIMBAL_DEVICE_ATTITUDE_STATUS), in the
  // gimbal protocol's vehicle frame: roll and pitch relative to the horizon, yaw relative to the
  // vehicle's heading (clockwise; a report in the earth frame is turned back by its delta_yaw).
  // Tait-Bryan z-y'-x'' angles as in ATTITUDE; vehicle time (time_boot_ms) of the report.
  bool has_gimbal_attitude = false;
  double gimbal_attitude_time_s = 0.0;
  double gimbal_attitude_roll_rad = 0.0, gimbal_attitude_pitch_rad = 0.0,
         gimbal_attitude_yaw_rad = 0.0;
  // mission (MISSION_CURRENT / MISSION_ITEM_REACHED)
  int mission_current = -1;
  int mission_last_reached = -1;
};

// One mission item (MISSION_ITEM_INT). Item 0 (home) is added by upload_mission(), as ArduPilot expects.
struct MissionItem {
  std::uint16_t command = 16;  // MAV_CMD (16 NAV_WAYPOINT, 22 NAV_TAKEOFF, 21 NAV_LAND, 20 RTL, ...)
  std::uint8_t frame = 6;      // MAV_FRAME (6 GLOBAL_RELATIVE_ALT_INT, 5 GLOBAL_INT = AMSL)
  float param1 = 0, param2 = 0, param3 = 0, param4 = 0;
  double lat_deg = 0.0, lon_deg = 0.0;
  float alt_m = 0.0f;
  bool autocontinue = true;

  static MissionItem takeoff(double rel_alt_m);
  static MissionItem waypoint(double lat_deg, double lon_deg, double rel_alt_m, double hold_s = 0.0);
  static MissionItem land();
  static MissionItem rtl();
};

struct VehicleConfig {
  std::uint8_t gcs_sysid = 255;      // ArduPilot's SYSID_MYGCS default
  std::uint8_t gcs_compid = 190;     // MAV_COMP_ID_MISSIONPLANNER
  std::uint8_t target_sysid = 0;     // 0: the first vehicle heard
  double heartbeat_period_s = 1.0;
  double telemetry_rate_hz = 10.0;   // position and attitude streams requested on connect
  double command_timeout_s = 1.0;    // per attempt, loop clock
  int command_attempts = 3;
  double setpoint_resend_s = 0.5;    // velocity/yaw-rate setpoints are re-sent (ArduCopter stops after ~3 s)
  // Simulation only (lockstep `done`): the vehicle's name or index in the simulator. Empty: sysid - 1
  // (the index under uavsim-server's / sim_vehicle.py's --auto-sysid).
  std::string sim_vehicle;
};

class Vehicle {
 public:
  explicit Vehicle(EventLoop& loop, VehicleConfig config = {});
  ~Vehicle();
  Vehicle(const Vehicle&) = delete;
  Vehicle& operator=(const Vehicle&) = delete;

  // Connects to "tcp:HOST:PORT" (or "HOST:PORT"), "udp:HOST:PORT" (datagrams to a vehicle listening
  // there, e.g. uavsim-server --out udpin:HOST:PORT or mavlink-router) or "udpin:ADDR:PORT" (listen there
  // for a vehicle that sends, e.g. uavsim-server --out udp:ADDR:PORT), and waits for the vehicle's first
  // heartbeat, then asks for telemetry streams. TCP: kConnectionRefused at once if nothing listens;
  // kTimeout after timeout_s (over UDP, no answer is only ever a timeout).
  // Can be called again after the link was lost (a restarted mission process takes over the same way).
  Result<void> connect(const std::string& address, double timeout_s = 10.0);
  // UAVSIM_MAVLINK (e.g. "tcp:127.0.0.1:5760"), else fallback.
  static std::string address_from_env(const std::string& fallback = "tcp:127.0.0.1:5760");
  void disconnect();
  bool connected() const;

  // Waits until the vehicle is ready to fly: heartbeat, home position, GPS 3D fix, EKF horizontal position
  // and pre-arm checks healthy.
  Result<void> wait_ready(double timeout_s = 60.0);
  bool ready() const;

  const Telemetry& telemetry() const;
  // Called on the loop thread after every telemetry update / every STATUSTEXT.
  void on_telemetry(std::function<void(const Telemetry&)> fn);
  void on_status_text(std::function<void(int severity, const std::string& text)> fn);
  const std::vector<std::string>& status_texts() const;  // the last 100

  // Commands: COMMAND_LONG/SET_MODE with COMMAND_ACK, retried on silence. kDenied / kFailed / kUnsupported /
  // kTemporarilyRejected carry the vehicle's MAV_RESULT.
  Result<void> set_mode(FlightMode mode);
  Result<void> arm(bool force = false);
  Result<void> disarm(bool force = false);
  // NAV_TAKEOFF to rel_alt_m above home (needs GUIDED and armed). With wait, returns once the vehicle is
  // within 0.5 m of that altitude (timeout_s).
  Result<void> takeoff(double rel_alt_m, bool wait = true, double timeout_s = 60.0);
  Result<void> land(bool wait = false, double timeout_s = 120.0);  // wait: until disarmed on the ground
  Result<void> return_to_launch();

  // Non-blocking forms, for a program that flies several vehicles from one event loop: a blocking command
  // runs the loop until its ack, so the program's other vehicles would wait meanwhile and step later than
  // they would alone. The command is sent now and retried on silence as above; done (optional) runs on the
  // loop thread with the outcome, never inside the call. A command with the same id while one is pending
  // replaces it (the first's done gets kCancelled). Link lost or closed: kConnectionLost. Destroying the
  // Vehicle drops pending callbacks without calling them.
  void command_long_async(std::uint16_t command, const std::array<float, 7>& params,
                          std::function<void(Result<void>)> done = {});
  void set_mode_async(FlightMode mode, std::function<void(Result<void>)> done = {});
  void arm_async(std::function<void(Result<void>)> done = {});
  void takeoff_async(double rel_alt_m, std::function<void(Result<void>)> done = {});  // needs GUIDED, armed
  void land_async(std::function<void(Result<void>)> done = {});

  // GUIDED setpoints (SET_POSITION_TARGET_*; ArduCopter does not acknowledge them: kNotReady if the vehicle
  // is not in GUIDED). yaw_rad is NaN to keep the heading; ENU yaw: counter-clockwise from east.
  Result<void> goto_local_enu(const Eigen::Vector3d& enu_m, double yaw_enu_rad = std::numeric_limits<double>::quiet_NaN());
  Result<void> goto_local_ned(const Eigen::Vector3d& ned_m, double yaw_ned_rad = std::numeric_limits<double>::quiet_NaN());
  Result<void> goto_geodetic(const Geodetic& point_amsl, double yaw_ned_rad = std::numeric_limits<double>::quiet_NaN());
  // Waits until the local position is within tolerance_m of enu_m (loop clock).
  Result<void> wait_position_enu(const Eigen::Vector3d& enu_m, double tolerance_m, double timeout_s);
  // Velocity in local ENU (m/s) with an optional yaw rate (rad/s, ENU: counter-clockwise positive) or
  // absolute yaw; re-sent every setpoint_resend_s until another command replaces it or stop() is called.
  Result<void> set_velocity_enu(const Eigen::Vector3d& v_m_s,
                                double yaw_rate_enu_rad_s = std::numeric_limits<double>::quiet_NaN());
  Result<void> set_velocity_enu_yaw(const Eigen::Vector3d& v_m_s, double yaw_enu_rad);
  // Ends a velocity command: hold the current position.
  Result<void> stop();
  // CONDITION_YAW: absolute heading (degrees clockwise from north) or relative (clockwise positive).
  Result<void> set_yaw(double heading_deg, double rate_deg_s = 30.0, bool relative = false);
  // DO_MOUNT_CONTROL (MAVLink targeting): pitch up positive, yaw relative to the vehicle, degrees.
  Result<void> point_gimbal(double pitch_deg, double yaw_deg, double roll_deg = 0.0);

  // Mission protocol (MISSION_COUNT / MISSION_REQUEST[_INT] / MISSION_ITEM_INT / MISSION_ACK). kDenied with
  // the MAV_MISSION_RESULT when the vehicle refuses it.
  Result<void> upload_mission(const std::vector<MissionItem>& items, double timeout_s = 10.0);
  // MISSION_START (the vehicle switches to AUTO; arm first).
  Result<void> start_mission();

  // Parameters (PARAM_REQUEST_READ / PARAM_SET, answered with PARAM_VALUE). An unknown name is kTimeout
  // (ArduPilot ignores it silently) with the name in the message.
  Result<float> get_param(const std::string& name, double timeout_s = 3.0);
  Result<float> set_param(const std::string& name, float value, double timeout_s = 3.0);

  // Any COMMAND_LONG (escape hatch), acknowledged.
  Result<void> command_long(std::uint16_t command, const std::array<float, 7>& params);

  EventLoop& loop();
 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace uavsim::client
