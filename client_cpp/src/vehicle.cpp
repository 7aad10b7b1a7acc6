// Vehicle: the façade over its capabilities, each a unit of its own on one MAVLink link
// (docs/mavlink.md says how the server's vehicles answer, as ArduCopter does):
//   MavlinkLink       socket, parser, seq, heartbeat, lockstep hold; routes frames by message id
//   TelemetryDecoder  stream requests and the telemetry cache
//   CommandSender     COMMAND_LONG/COMMAND_ACK with retries (blocking = async + a wait)
//   MissionUploader   the mission upload protocol
//   ParamClient       PARAM_REQUEST_READ / PARAM_SET
//   GuidedSetpoints   SET_POSITION_TARGET_* with the velocity re-send
// Here: argument checks, the order of steps of each public call, and what the Telemetry cache
// assumes after an accepted command until the next heartbeat says it.
#include "uavsim/client/vehicle.hpp"

#include <cmath>
#include <cstdlib>
#include <limits>
#include <optional>
#include <sstream>
#include <string>

#include "command_sender.hpp"
#include "guided_setpoints.hpp"
#include "mavlink_link.hpp"
#include "mission_uploader.hpp"
#include "param_client.hpp"
#include "telemetry_decoder.hpp"
#include "uavsim/common/mavlink/force_arm.hpp"
#include "uavsim/common/mavlink/generated/enum_names.hpp"
#include "uavsim/common/mavlink/generated/enums.hpp"

namespace uavsim::client {

namespace mav = common::mavlink;
using mav::MavCmd;
using mav::to_underlying;
using Params = CommandSender::Params;

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
// take-off with wait: done within this of the target altitude
constexpr double kTakeoffAltitudeToleranceM = 0.5;

// FlightMode is ArduCopter's mode numbering, which the dialect's COPTER_MODE names
static_assert(
    static_cast<std::uint32_t>(FlightMode::kGuided) == to_underlying(mav::CopterMode::Guided) &&
    static_cast<std::uint32_t>(FlightMode::kLand) == to_underlying(mav::CopterMode::Land) &&
    static_cast<std::uint32_t>(FlightMode::kTurtle) == to_underlying(mav::CopterMode::Turtle));

Params set_mode_params(FlightMode mode) {
  // param1: the mode flags (custom mode), param2: the custom mode
  const auto flags = static_cast<float>(to_underlying(mav::MavModeFlag::CustomModeEnabled));
  return {flags, static_cast<float>(static_cast<std::uint32_t>(mode)), 0, 0, 0, 0, 0};
}
Params arm_params(bool arm, bool force) {
  const float magic = !force ? 0.0f : arm ? mav::kForceArmMagic : mav::kForceArmDisarmMagic;
  return {arm ? 1.0f : 0.0f, magic, 0, 0, 0, 0, 0};
}
Params takeoff_params(double rel_alt_m) {
  return {0, 0, 0, 0, 0, 0, static_cast<float>(rel_alt_m)};
}

// a refused command's failure, with what the caller was doing in front
Result<void> failed(const std::string& doing, const Result<void>& r) {
  return Result<void>::fail(r.code(), doing + ": " + r.message(), r.error().mav_result);
}

}  // namespace

const char* mode_name(FlightMode m) {
  const std::string_view name = mav::enum_name(static_cast<mav::CopterMode>(m));
  return name.empty() ? "UNKNOWN" : name.data();  // the generated names are string literals
}

// ------------------------------------------------------------------------------------------ Impl

struct Vehicle::Impl {
  EventLoop& loop;
  VehicleConfig config;
  MavlinkLink link{loop, config};
  TelemetryDecoder telemetry{loop, link};
  CommandSender commands{loop, link, config};
  MissionUploader mission{loop, link};
  ParamClient params{loop, link};
  GuidedSetpoints setpoints{loop, link, config.setpoint_resend_s};
  std::function<void(const Telemetry&)> on_telemetry;

  Impl(EventLoop& l, VehicleConfig c) : loop(l), config(std::move(c)) {
    telemetry.on_changed([this] {
      // stale velocity re-sends must not resume when someone switches back to GUIDED later
      if (tm().mode != FlightMode::kGuided) setpoints.cancel();
      if (on_telemetry) on_telemetry(tm());
    });
    link.on_closed([this](const char* why) {
      telemetry.stop();
      setpoints.cancel();
      commands.fail_all(why != nullptr ? std::string("the link was lost: ") + why
                                       : "the link was closed");
      mission.abort();
    });
  }

  Telemetry& tm() { return telemetry.telemetry(); }

  Result<void> need_guided() {
    if (auto r = link.need_open(); !r) return r;
    if (tm().mode != FlightMode::kGuided) {
      return Result<void>::fail(
          Error::kNotReady,
          std::string("setpoints need GUIDED; the vehicle is in ") + mode_name(tm().mode));
    }
    return {};
  }

  // the mode the vehicle accepted, until its next heartbeat says it
  void note_mode(FlightMode mode) {
    tm().mode = mode;
    tm().custom_mode = static_cast<std::uint32_t>(mode);
  }

  // waits on the loop for pred; kConnectionLost when the link is lost meanwhile
  Result<void> wait_on_link(const std::function<bool()>& pred, double timeout_s,
                            const std::string& what) {
    auto w = loop.run_until([&] { return !link.is_open() || pred(); }, timeout_s, what);
    if (!link.is_open())
      return Result<void>::fail(Error::kConnectionLost, "the link was lost waiting for " + what);
    return w;
  }

  bool ready_now() {
    // an armed vehicle (taken over in flight) is past its pre-arm checks
    const Telemetry& t = tm();
    return link.is_open() && t.heartbeat_seen && t.home_set &&
           t.gps_fix_type >= static_cast<int>(to_underlying(mav::GpsFixType::Type3dFix)) &&
           t.ekf_ok && (t.prearm_ok || t.armed);
  }
};

// --------------------------------------------------------------------------------------- Vehicle

Vehicle::Vehicle(EventLoop& loop, VehicleConfig config)
    : impl_(std::make_unique<Impl>(loop, std::move(config))) {
  loop.assert_in_loop_thread();
}

Vehicle::~Vehicle() {
  // pending non-blocking commands end silently: their callbacks may reach this vehicle
  impl_->commands.drop_all();
  impl_->link.close(nullptr);
}

EventLoop& Vehicle::loop() { return impl_->loop; }

std::string Vehicle::address_from_env(const std::string& fallback) {
  const char* env = std::getenv("UAVSIM_MAVLINK");
  return env != nullptr && *env != '\0' ? std::string(env) : fallback;
}

Result<void> Vehicle::connect(const std::string& address, double timeout_s) {
  Impl& s = *impl_;
  s.loop.assert_in_loop_thread();
  const double start = s.loop.now();
  if (auto r = s.link.open(address, timeout_s); !r) return r;
  s.telemetry.reset();
  const double left = std::max(0.0, timeout_s - (s.loop.now() - start));
  auto w = s.loop.run_until([&s] { return s.tm().heartbeat_seen || !s.link.is_open(); }, left,
                            "the vehicle's heartbeat");
  if (!s.link.is_open()) {
    return Result<void>::fail(Error::kConnectionLost,
                              address + ": closed before a heartbeat arrived");
  }
  if (!w) {
    s.link.close(nullptr);
    return Result<void>::fail(w.code(), address + ": connected, but " + w.message());
  }
  s.telemetry.request_streams(s.config.telemetry_rate_hz);
  return {};
}

void Vehicle::disconnect() {
  impl_->loop.assert_in_loop_thread();
  impl_->link.close(nullptr);
}

bool Vehicle::connected() const { return impl_->link.is_open(); }
bool Vehicle::ready() const { return impl_->ready_now(); }
const Telemetry& Vehicle::telemetry() const { return impl_->telemetry.telemetry(); }
void Vehicle::on_telemetry(std::function<void(const Telemetry&)> fn) {
  impl_->on_telemetry = std::move(fn);
}
void Vehicle::on_status_text(std::function<void(int, const std::string&)> fn) {
  impl_->telemetry.on_status_text(std::move(fn));
}
const std::vector<std::string>& Vehicle::status_texts() const {
  return impl_->telemetry.status_texts();
}

Result<void> Vehicle::wait_ready(double timeout_s) {
  Impl& s = *impl_;
  s.loop.assert_in_loop_thread();
  if (auto r = s.link.need_open(); !r) return r;
  auto w = s.loop.run_until([&s] { return s.ready_now() || !s.link.is_open(); }, timeout_s,
                            "the vehicle to be ready");
  if (s.ready_now()) return {};
  if (!s.link.is_open()) {
    return Result<void>::fail(Error::kConnectionLost,
                              "the link was lost while waiting for the vehicle to be ready");
  }
  if (!w && w.code() != Error::kTimeout) return w;
  const Telemetry& t = s.tm();
  std::ostringstream os;
  os << "vehicle not ready after " << timeout_s << " s:";
  if (!t.home_set) os << " no home position;";
  if (t.gps_fix_type < static_cast<int>(to_underlying(mav::GpsFixType::Type3dFix))) {
    os << " GPS fix type " << t.gps_fix_type << ";";
  }
  if (!t.ekf_ok) os << " EKF has no horizontal position;";
  if (!t.prearm_ok && !t.armed) os << " pre-arm checks failing;";
  if (!status_texts().empty()) os << " last message: " << status_texts().back();
  return Result<void>::fail(Error::kTimeout, os.str());
}

Result<void> Vehicle::set_mode(FlightMode mode) {
  Impl& s = *impl_;
  if (mode != FlightMode::kGuided) s.setpoints.cancel();
  auto r = s.commands.send(MavCmd::DoSetMode, set_mode_params(mode));
  if (!r) return failed(std::string("set mode ") + mode_name(mode), r);
  s.note_mode(mode);
  return {};
}

Result<void> Vehicle::arm(bool force) {
  auto r = impl_->commands.send(MavCmd::ComponentArmDisarm, arm_params(true, force));
  if (!r) {
    std::string why = r.message();
    if (!status_texts().empty()) why += " (vehicle: " + status_texts().back() + ")";
    return Result<void>::fail(r.code(), "arm: " + why, r.error().mav_result);
  }
  impl_->tm().armed = true;
  return {};
}

Result<void> Vehicle::disarm(bool force) {
  impl_->setpoints.cancel();
  auto r = impl_->commands.send(MavCmd::ComponentArmDisarm, arm_params(false, force));
  if (!r) return failed("disarm", r);
  impl_->tm().armed = false;
  return {};
}

Result<void> Vehicle::takeoff(double rel_alt_m, bool wait, double timeout_s) {
  Impl& s = *impl_;
  if (!std::isfinite(rel_alt_m) || rel_alt_m <= 0) {
    return Result<void>::fail(Error::kInvalidArgument, "take-off altitude must be > 0");
  }
  s.setpoints.cancel();
  auto r = s.commands.send(MavCmd::NavTakeoff, takeoff_params(rel_alt_m));
  if (!r) return failed("take-off", r);
  if (!wait) return {};
  return s.loop.run_until(
      [&] {
        return !s.link.is_open() ||
               (s.tm().has_global_position &&
                std::abs(s.tm().relative_alt_m - rel_alt_m) < kTakeoffAltitudeToleranceM);
      },
      timeout_s, "take-off altitude " + std::to_string(rel_alt_m) + " m");
}

void Vehicle::command_long_async(std::uint16_t command, const std::array<float, 7>& params,
                                 std::function<void(Result<void>)> done) {
  impl_->commands.send_async(command, params, std::move(done));
}

void Vehicle::set_mode_async(FlightMode mode, std::function<void(Result<void>)> done) {
  Impl& s = *impl_;
  if (mode != FlightMode::kGuided) s.setpoints.cancel();
  s.commands.send_async(MavCmd::DoSetMode, set_mode_params(mode),
                        [&s, mode, done = std::move(done)](Result<void> r) {
                          if (r) s.note_mode(mode);
                          if (done) done(r);
                        });
}

void Vehicle::arm_async(std::function<void(Result<void>)> done) {
  Impl& s = *impl_;
  s.commands.send_async(MavCmd::ComponentArmDisarm, arm_params(true, false),
                        [&s, done = std::move(done)](Result<void> r) {
                          if (r) s.tm().armed = true;
                          if (done) done(r);
                        });
}

void Vehicle::takeoff_async(double rel_alt_m, std::function<void(Result<void>)> done) {
  Impl& s = *impl_;
  if (!std::isfinite(rel_alt_m) || rel_alt_m <= 0) {
    auto r = Result<void>::fail(Error::kInvalidArgument, "take-off altitude must be > 0");
    if (done) s.loop.post([done = std::move(done), r] { done(r); });
    return;
  }
  s.setpoints.cancel();
  s.commands.send_async(MavCmd::NavTakeoff, takeoff_params(rel_alt_m), std::move(done));
}

void Vehicle::land_async(std::function<void(Result<void>)> done) {
  impl_->setpoints.cancel();
  impl_->commands.send_async(MavCmd::NavLand, {}, std::move(done));
}

Result<void> Vehicle::land(bool wait, double timeout_s) {
  Impl& s = *impl_;
  s.setpoints.cancel();
  auto r = s.commands.send(MavCmd::NavLand, {});
  if (!r) return failed("land", r);
  if (!wait) return {};
  auto w = s.loop.run_until(
      [&] { return !s.link.is_open() || (s.tm().mode == FlightMode::kLand && !s.tm().armed); },
      timeout_s, "landing and disarm");
  if (!s.link.is_open())
    return Result<void>::fail(Error::kConnectionLost, "land: the link was lost");
  return w;
}

Result<void> Vehicle::return_to_launch() {
  impl_->setpoints.cancel();
  auto r = impl_->commands.send(MavCmd::NavReturnToLaunch, {});
  if (!r) return failed("RTL", r);
  impl_->tm().mode = FlightMode::kRtl;
  return {};
}

Result<void> Vehicle::goto_local_ned(const Eigen::Vector3d& ned_m, double yaw_ned_rad) {
  Impl& s = *impl_;
  s.loop.assert_in_loop_thread();
  if (!ned_m.allFinite())
    return Result<void>::fail(Error::kInvalidArgument, "goto: position must be finite");
  if (auto r = s.need_guided(); !r) return r;
  return s.setpoints.position_ned(
      ned_m, std::isfinite(yaw_ned_rad) ? std::optional(yaw_ned_rad) : std::nullopt);
}

Result<void> Vehicle::goto_local_enu(const Eigen::Vector3d& enu_m, double yaw_enu_rad) {
  return goto_local_ned(ned_from_enu(enu_m),
                        std::isfinite(yaw_enu_rad) ? ned_yaw_from_enu(yaw_enu_rad) : kNaN);
}

Result<void> Vehicle::goto_geodetic(const Geodetic& p, double yaw_ned_rad) {
  Impl& s = *impl_;
  s.loop.assert_in_loop_thread();
  if (!std::isfinite(p.lat_deg) || !std::isfinite(p.lon_deg) || !std::isfinite(p.alt_m) ||
      std::abs(p.lat_deg) > 90 || std::abs(p.lon_deg) > 180) {
    return Result<void>::fail(Error::kInvalidArgument, "goto: invalid latitude/longitude/altitude");
  }
  if (auto r = s.need_guided(); !r) return r;
  return s.setpoints.position_global(
      p, std::isfinite(yaw_ned_rad) ? std::optional(yaw_ned_rad) : std::nullopt);
}

Result<void> Vehicle::wait_position_enu(const Eigen::Vector3d& enu_m, double tolerance_m,
                                        double timeout_s) {
  Impl& s = *impl_;
  std::ostringstream what;
  what << "position (" << enu_m.x() << ", " << enu_m.y() << ", " << enu_m.z() << ") ENU within "
       << tolerance_m << " m";
  return s.wait_on_link(
      [&] {
        return s.tm().has_local_position && (s.tm().position_enu_m - enu_m).norm() < tolerance_m;
      },
      timeout_s, what.str());
}

Result<void> Vehicle::set_velocity_enu(const Eigen::Vector3d& v, double yaw_rate_enu_rad_s) {
  Impl& s = *impl_;
  s.loop.assert_in_loop_thread();
  if (!v.allFinite() || v.norm() > 100.0) {
    return Result<void>::fail(Error::kInvalidArgument, "velocity must be finite and < 100 m/s");
  }
  if (auto r = s.need_guided(); !r) return r;
  // NED yaw rate is clockwise
  const auto rate =
      std::isfinite(yaw_rate_enu_rad_s) ? std::optional(-yaw_rate_enu_rad_s) : std::nullopt;
  return s.setpoints.velocity_ned(ned_from_enu(v), std::nullopt, rate);
}

Result<void> Vehicle::set_velocity_enu_yaw(const Eigen::Vector3d& v, double yaw_enu_rad) {
  Impl& s = *impl_;
  s.loop.assert_in_loop_thread();
  if (!v.allFinite() || !std::isfinite(yaw_enu_rad)) {
    return Result<void>::fail(Error::kInvalidArgument, "velocity and yaw must be finite");
  }
  if (auto r = s.need_guided(); !r) return r;
  return s.setpoints.velocity_ned(ned_from_enu(v), ned_yaw_from_enu(yaw_enu_rad), std::nullopt);
}

Result<void> Vehicle::stop() {
  Impl& s = *impl_;
  s.loop.assert_in_loop_thread();
  s.setpoints.cancel();
  if (auto r = s.need_guided(); !r) return r;
  // hold here: position target at the current position
  return s.setpoints.position_ned(s.tm().position_ned_m, std::nullopt);
}

Result<void> Vehicle::set_yaw(double heading_deg, double rate_deg_s, bool relative) {
  if (!std::isfinite(heading_deg) || !std::isfinite(rate_deg_s)) {
    return Result<void>::fail(Error::kInvalidArgument, "yaw must be finite");
  }
  // CONDITION_YAW: angle (deg), rate (deg/s), direction (-1 counter-clockwise, 1 clockwise; 0 for
  // absolute), relative (1) or absolute (0)
  float angle = static_cast<float>(heading_deg);
  float dir = 0.0f;
  if (relative) {
    dir = heading_deg < 0 ? -1.0f : 1.0f;
    angle = static_cast<float>(std::abs(heading_deg));
  } else {
    angle = static_cast<float>(std::fmod(std::fmod(heading_deg, 360.0) + 360.0, 360.0));
  }
  auto r = impl_->commands.send(MavCmd::ConditionYaw, {angle, static_cast<float>(rate_deg_s), dir,
                                                       relative ? 1.0f : 0.0f, 0, 0, 0});
  if (!r) return failed("yaw", r);
  return {};
}

Result<void> Vehicle::point_gimbal(double pitch_deg, double yaw_deg, double roll_deg) {
  if (!std::isfinite(pitch_deg) || !std::isfinite(yaw_deg) || !std::isfinite(roll_deg)) {
    return Result<void>::fail(Error::kInvalidArgument, "gimbal angles must be finite");
  }
  // DO_MOUNT_CONTROL: pitch, roll, yaw (deg), the mount mode in param7
  const auto mode = static_cast<float>(to_underlying(mav::MavMountMode::MavlinkTargeting));
  auto r = impl_->commands.send(MavCmd::DoMountControl,
                                {static_cast<float>(pitch_deg), static_cast<float>(roll_deg),
                                 static_cast<float>(yaw_deg), 0, 0, 0, mode});
  if (!r) return failed("gimbal", r);
  return {};
}

Result<void> Vehicle::command_long(std::uint16_t command, const std::array<float, 7>& params) {
  return impl_->commands.send(command, params);
}

Result<void> Vehicle::upload_mission(const std::vector<MissionItem>& items, double timeout_s) {
  return impl_->mission.upload(items, impl_->tm().home, timeout_s);
}

Result<void> Vehicle::start_mission() {
  impl_->setpoints.cancel();
  auto r = impl_->commands.send(MavCmd::MissionStart, {0, 0, 0, 0, 0, 0, 0});
  if (!r) return failed("mission start", r);
  impl_->tm().mode = FlightMode::kAuto;
  return {};
}

Result<float> Vehicle::get_param(const std::string& name, double timeout_s) {
  return impl_->params.get(name, timeout_s);
}

Result<float> Vehicle::set_param(const std::string& name, float value, double timeout_s) {
  return impl_->params.set(name, value, timeout_s);
}

}  // namespace uavsim::client
