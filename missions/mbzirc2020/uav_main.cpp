// mbzirc2020-uav: one balloon-popping UAV (seed 7.2): its own MAVLink link, its camera, its GCS
// link, and the strategy FSM (vehicle_fsm.hpp) stepped at 20 Hz on the event loop. The same program
// would fly a real drone (the camera frames then come from its driver); UAVSIM_LOCKSTEP puts it on
// sim time.
//
// usage: mbzirc2020-uav --index I --mavlink tcp:HOST:PORT --gcs HOST:PORT [--camera NAME]
// [--vehicle NAME] [--video-log FILE.vlog]
// --video-log: every camera frame with what the vision saw drawn on it (the detections' circles and
// ranges, the confirmed balloons' count), vision/'s VLOG (uavsim-videolog-export makes an MP4 of
// it); written on its own thread, it changes nothing the UAV decides.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <optional>
#include <string>

#include "balloon_perception.hpp"
#include "messages.hpp"
#include "mission_config.hpp"
#include "uavsim/client/camera.hpp"
#include "uavsim/client/event_loop.hpp"
#include "uavsim/client/gcs_link.hpp"
#include "uavsim/client/vehicle.hpp"
#include "uavsim/common/angles.hpp"
#include "uavsim/common/parse_number.hpp"
#include "uavsim/mission/camera_frames.hpp"
#include "uavsim/mission/program.hpp"
#include "uavsim/mission/vehicle_camera.hpp"
#include "uavsim/vision/video_log.hpp"
#include "vehicle_fsm.hpp"

using namespace uavsim::client;
using uavsim::mission::TimedPose;
using namespace uavsim::missions::mbzirc2020;

namespace {

constexpr double kStep_s = 0.05;         // FSM rate 20 Hz
constexpr double kStatusPeriod_s = 0.5;  // STATUS to the GCS
constexpr double kLinger_s = 3.0;        // keep reporting after the end, so the GCS hears it
// GIMBAL_DEVICE_ATTITUDE_STATUS (285) asked for every 20 ms with MAV_CMD_SET_MESSAGE_INTERVAL
// (511): the field gimbal's error changes within its 50 ms loop, and EXTRA3's default 2 Hz is far
// too slow
constexpr uint16_t kSetMessageInterval = 511;
constexpr float kGimbalDeviceAttitudeStatus = 285;
constexpr float kGimbalReportInterval_us = 20000;
// a frame with no report this close before it is placed with the commanded elevation
constexpr double kGimbalReportMaxAge_s = 0.1;

int usage() {
  std::fprintf(
      stderr,
      "usage: mbzirc2020-uav --index I --mavlink tcp:HOST:PORT --gcs HOST:PORT [--camera NAME] "
      "[--vehicle NAME] [--video-log FILE.vlog]\n");
  return 2;
}

struct Options : uavsim::mission::VehicleProgramOptions {
  int index = -1;
  std::string gcs_host;
  int gcs_port = 0;
};

// the command line; nullopt: not usable (usage)
std::optional<Options> parse_options(int argc, char** argv) {
  Options o;
  std::string gcs;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string a = argv[i];
    if (a == "--index") {
      if (!uavsim::common::parse_integer(argv[i + 1], 0, 1, &o.index)) return std::nullopt;
    } else if (a == "--gcs") {
      gcs = argv[i + 1];
    } else if (!uavsim::mission::parse_vehicle_program_option(a, argv[i + 1], &o)) {
      return std::nullopt;
    }
  }
  const size_t colon = gcs.rfind(':');
  // argc even: an option without its value (or a lone --help), which the pairs above skipped
  if (argc % 2 == 0 || o.index < 0 || o.mavlink.empty() || colon == std::string::npos ||
      !uavsim::common::parse_integer(gcs.c_str() + colon + 1, 1, 65535, &o.gcs_port))
    return std::nullopt;
  o.gcs_host = gcs.substr(0, colon);
  if (o.vehicle.empty()) o.vehicle = "uav" + std::to_string(o.index);
  if (o.camera.empty()) o.camera = o.vehicle + "_front";
  return o;
}

// what the vision saw in a frame, for the video log: each detection's circle and range, the
// confirmed balloons
uavsim::vision::VideoLogFrame vision_log_frame(const CameraFrame& f,
                                               const BalloonPerception& perception, int seen,
                                               const std::string& me) {
  uavsim::vision::VideoLogFrame frame;
  frame.stamp_us = static_cast<int64_t>(std::llround(f.stamp_s * 1e6));
  frame.image = f.image;
  const cv::Scalar magenta(255, 0, 255);  // BGR: stands out on green balloons and grass
  for (const uavsim::vision::BalloonDetection& d : perception.last_detections()) {
    const cv::Point2f c(static_cast<float>(d.centre_px.x), static_cast<float>(d.centre_px.y));
    frame.overlays.push_back(
        uavsim::vision::Overlay::circle(c, static_cast<float>(d.radius_px) + 2.0f, magenta, 2.0f));
    char range[32];
    std::snprintf(range, sizeof(range), "%.1f m", d.range_m);
    frame.overlays.push_back(uavsim::vision::Overlay::label(
        c + cv::Point2f(static_cast<float>(d.radius_px) + 4.0f, 0.0f), range, magenta, 0.4f));
  }
  char text[96];
  std::snprintf(text, sizeof(text), "%s t=%.2f detections %d confirmed %zu", me.c_str(), f.stamp_s,
                seen, perception.sightings().size());
  frame.text = text;
  return frame;
}

// a camera frame into the perception (placed by the telemetry moved to its stamp and the gimbal's
// report of its exposure), and into the video log if there is one. The frames' stamps and the
// vehicle's time_boot_ms share the sim clock here; on a drone the camera driver's clock would be
// mapped onto the autopilot's (TIMESYNC).
void on_camera_frame(const CameraFrame& f, const TimedPose& pose, const GimbalReports& gimbal,
                     BalloonPerception& perception, uavsim::vision::VideoLogWriter* vlog,
                     const std::string& me) {
  if (pose.time_s < 0) return;
  const Eigen::Vector3d p = pose.position_at(f.stamp_s);
  const uavsim::vision::PinholeIntrinsics k = uavsim::mission::intrinsics_of(f);
  const std::optional<double> pitch_rad = perception.camera_pitch_at(f.stamp_s);
  if (!pitch_rad) return;  // the gimbal is slewing
  const std::optional<GimbalReport> report = gimbal.at(f.stamp_s, kGimbalReportMaxAge_s);
  const int seen =
      perception.on_frame(f.image, k, f.stamp_s,
                          report ? perception.camera_pose(p, pose.yaw_enu_rad, *report)
                                 : perception.camera_pose(p, pose.yaw_enu_rad, *pitch_rad));
  // a full queue drops the frame, never waits
  if (vlog) (void)vlog->submit(vision_log_frame(f, perception, seen, me));
}

// the FSM's inputs: telemetry, sightings, and the GCS messages received since the last step
VehicleInputs vehicle_inputs(double now_s, const Telemetry& t, const BalloonPerception& perception,
                             GcsLink& link) {
  VehicleInputs in;
  in.now_s = now_s;
  in.armed = t.armed;
  in.on_ground = t.landed == LandedState::kOnGround;
  in.position_enu_m = t.position_enu_m;
  in.velocity_enu_m_s = t.velocity_enu_m_s;
  in.yaw_enu_rad = enu_yaw_from_ned(t.yaw_rad);
  in.roll_rad = t.roll_rad;
  in.pitch_rad = t.pitch_rad;
  in.balloons = perception.sightings();
  for (const GcsMessage& m : link.take_received()) {
    if (m.topic == kTopicState) {
      if (auto c = decode_command(m.payload)) in.commands.push_back(*c);
    } else if (m.topic == kTopicAirspace) {
      if (auto a = decode_airspace(m.payload)) in.airspace_replies.push_back(*a);
    }
  }
  return in;
}

// the STATUS the GCS reads (seed 7.2's topic)
UavStatus status_of(const VehicleFsm& fsm, bool ready, const Telemetry& t) {
  UavStatus s;
  s.state = static_cast<uint8_t>(fsm.state());
  s.ready = fsm.state() == VehicleState::kPreflight && ready;
  s.failed = fsm.state() == VehicleState::kFailed;
  s.landed = fsm.state() == VehicleState::kLanded;
  s.position_enu_m = t.position_enu_m;
  s.popped = static_cast<uint8_t>(fsm.popped());
  return s;
}

}  // namespace

int main(int argc, char** argv) {
  const std::optional<Options> o = parse_options(argc, argv);
  if (!o) return usage();
  const std::string& me = o->vehicle;
  const int index = o->index;

  auto started = uavsim::mission::start_vehicle_program(me, o->mavlink);
  if (!started) return 1;
  uavsim::mission::ProgramLoop& program = *started->program;
  EventLoop& loop = program.loop();
  Vehicle& uav = *started->vehicle;

  // the ground-station link (seed 6.3)
  std::string error;
  auto link =
      GcsLink::open(GcsLinkConfig{static_cast<uint8_t>(index)},
                    {"127.0.0.1", 0, o->gcs_host, static_cast<uint16_t>(o->gcs_port)}, &error);
  if (!link) {
    program.log("GCS link: " + error);
    return 1;
  }
  (void)loop.watch_fd(link->fd(), EventLoop::kReadable,
                      [&](uint32_t) { link->service(program.now_us()); });

  TimedPose pose;
  GimbalReports gimbal_reports;
  uav.on_telemetry([&](const Telemetry& t) {
    if (t.has_gimbal_attitude) {
      gimbal_reports.add({t.gimbal_attitude_time_s, t.gimbal_attitude_roll_rad,
                          t.gimbal_attitude_pitch_rad, t.gimbal_attitude_yaw_rad});
    }
    if (!t.has_local_position) return;
    pose = {loop.now(), t.position_enu_m, t.velocity_enu_m_s, enu_yaw_from_ned(t.yaw_rad)};
  });

  // the forward camera on its stabilised gimbal: straight ahead, a few degrees down (seed 7.2:
  // level; mission_config.hpp says why)
  const MissionConfig config;
  BalloonPerception perception(config);
  std::unique_ptr<uavsim::vision::VideoLogWriter> vlog;
  if (!uavsim::mission::open_video_log(program, o->video_log, &vlog)) return 1;
  const auto sub = uavsim::mission::subscribe_camera(
      program, o->camera, CameraFormat::kBgr, [&](const CameraFrame& f) {
        on_camera_frame(f, pose, gimbal_reports, perception, vlog.get(), me);
      });
  if (!sub) return 1;

  if (!uavsim::mission::wait_vehicle_ready(program, uav, 120)) return 1;
  if (auto r = uav.command_long(kSetMessageInterval, {kGimbalDeviceAttitudeStatus,
                                                      kGimbalReportInterval_us, 0, 0, 0, 0, 0});
      !r) {
    program.log("gimbal reports: " + r.message() + " (frames placed with the commanded elevation)");
  }
  // the gimbal follows the FSM's wanted elevation; if it refuses, the camera stays level
  bool gimbal_ok = true;
  double gimbal_pitch_rad = 0.0;
  auto point_camera = [&](double pitch_rad) {
    if (!gimbal_ok || pitch_rad == gimbal_pitch_rad) return;
    perception.set_camera_pitch(pitch_rad, loop.now());
    if (auto r = uav.point_gimbal(pitch_rad * 180.0 / uavsim::common::kPi, 0.0); !r) {
      program.log("gimbal: " + r.message() + " (keeping it level)");
      gimbal_ok = false;
      perception.set_camera_pitch(0.0, loop.now());
    }
    gimbal_pitch_rad = pitch_rad;
  };
  point_camera(config.camera_pitch_rad);
  const Eigen::Vector2d home = uav.telemetry().position_enu_m.head<2>();
  const Side side = index == 0 ? Side::kSouth : Side::kNorth;
  VehicleFsm fsm(config, index, side, home);
  program.log(std::string("ready at (") + std::to_string(home.x()).substr(0, 6) + ", " +
              std::to_string(home.y()).substr(0, 6) + "), side " +
              (side == Side::kSouth ? "south" : "north") + ": waiting for the GCS start");

  double last_status_s = -1e9, end_s = -1.0;
  VehicleState last_state = fsm.state();
  while (end_s < 0 || loop.now() < end_s + kLinger_s) {
    if (auto r = loop.run_for(kStep_s); !r) {
      program.log("clock: " + r.message());
      return 1;
    }
    link->service(program.now_us());

    // inputs: telemetry, sightings, GCS messages; outputs: setpoints and GCS messages
    const Telemetry& t = uav.telemetry();
    const VehicleOutputs out = fsm.step(vehicle_inputs(loop.now(), t, perception, *link));
    if (!out.note.empty()) program.log(out.note);
    point_camera(out.camera_pitch_rad);
    // a failed vehicle's refused setpoints are expected: not logged
    uavsim::mission::fly(program, uav, out, out.yaw_enu_rad, fsm.state() != VehicleState::kFailed);
    if (out.airspace) link->publish(kTopicAirspace, encode_airspace(*out.airspace));
    if (out.popped_enu_m) link->publish(kTopicPopped, encode_point(*out.popped_enu_m));
    if (fsm.state() != last_state || loop.now() - last_status_s >= kStatusPeriod_s) {
      last_state = fsm.state();
      last_status_s = loop.now();
      link->publish(kTopicStatus, encode_status(status_of(fsm, uav.ready(), t)));
    }
    if (end_s < 0 &&
        (fsm.state() == VehicleState::kLanded || fsm.state() == VehicleState::kFailed)) {
      end_s = loop.now();
      program.log(std::string("mission over: ") + vehicle_state_name(fsm.state()) + ", " +
                  std::to_string(fsm.popped()) + " balloon(s) pierced");
    }
  }
  loop.unwatch_fd(link->fd());
  return fsm.state() == VehicleState::kLanded ? 0 : 3;
}
