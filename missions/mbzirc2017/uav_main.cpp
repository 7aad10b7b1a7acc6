// mbzirc2017-uav: the MBZIRC 2017 landing UAV (seed 7.1): its MAVLink link, its down-looking camera
// (about 7 frames/s, each costing vision_latency_s of detached time, as the seed's TX1 did), its
// landing-pad microswitches, and the FSM of fig. 7.6 (landing_fsm.hpp) stepped at 20 Hz. The same
// program would fly a real drone (frames from its camera driver, switches from its GPIO);
// UAVSIM_LOCKSTEP puts it on sim time.
//
// usage: mbzirc2017-uav --mavlink tcp:HOST:PORT [--vehicle NAME] [--camera NAME] [--video-log
// FILE.vlog]
// --video-log: every processed camera frame with what the vision saw drawn on it (the marker's
// ring, whether the filter took it, the deck position it gave, the FSM state;
// detection_drawing.hpp)
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <opencv2/core.hpp>
#include <optional>
#include <string>

#include "detection_drawing.hpp"
#include "estimate_monitor.hpp"
#include "landing_fsm.hpp"
#include "mission_config.hpp"
#include "truck_perception.hpp"
#include "uavsim/client/camera.hpp"
#include "uavsim/client/event_loop.hpp"
#include "uavsim/client/geodesy.hpp"
#include "uavsim/client/switches.hpp"
#include "uavsim/client/vehicle.hpp"
#include "uavsim/mission/camera_frames.hpp"
#include "uavsim/mission/program.hpp"
#include "uavsim/mission/vehicle_camera.hpp"
#include "uavsim/vision/video_log.hpp"

using namespace uavsim::client;
using uavsim::mission::TimedPose;
using namespace uavsim::missions::mbzirc2017;

namespace {

constexpr double kStep_s = 0.05;             // FSM rate 20 Hz
constexpr double kLinger_s = 3.0;            // after Landed, before exiting
constexpr double kMaxExtrapolation_s = 0.5;  // of the telemetry's position to now
constexpr double kDarkFrameMean = 4.0;       // grey levels: below, a frame is black
constexpr double kBudget_s =
    900.0;  // the program gives up after this long (the run's own limit is shorter)

int usage() {
  std::fprintf(stderr,
               "usage: mbzirc2017-uav --mavlink tcp:HOST:PORT [--vehicle NAME] [--camera NAME] "
               "[--video-log FILE.vlog]\n");
  return 2;
}

using Options = uavsim::mission::VehicleProgramOptions;

// the command line; nullopt: not usable (usage)
std::optional<Options> parse_options(int argc, char** argv) {
  Options o;
  o.vehicle = "uav0";
  for (int i = 1; i + 1 < argc; i += 2) {
    if (!uavsim::mission::parse_vehicle_program_option(argv[i], argv[i + 1], &o))
      return std::nullopt;
  }
  if (o.mavlink.empty() || argc % 2 == 0) return std::nullopt;
  if (o.camera.empty()) o.camera = o.vehicle + "_down";
  return o;
}

// a camera frame waiting for the vision computer, with where the camera was when it was taken
struct Pending {
  cv::Mat grey;
  uavsim::vision::PinholeIntrinsics intrinsics;
  int64_t stamp_us = 0;
  uavsim::vision::CameraPose pose;
};

Pending pending_frame(const CameraFrame& f, const TimedPose& pose,
                      const TruckPerception& perception) {
  Pending p;
  p.grey = f.image;
  p.intrinsics = uavsim::mission::intrinsics_of(f);
  p.stamp_us = f.stamp_us;
  // where the vehicle was when the image was taken: the latest telemetry moved to the stamp
  p.pose = perception.camera_pose(pose.position_at(f.stamp_s), pose.yaw_enu_rad);
  return p;
}

// the FSM's inputs: telemetry, the pad switches, the camera's state and the truck as the camera
// pipeline knows it
FsmInputs fsm_inputs(double now_s, const Telemetry& t, const TimedPose& pose, bool switch_closed,
                     bool camera_dark, bool estimate_settling, const TruckPerception& perception) {
  FsmInputs in;
  in.now_s = now_s;
  in.armed = t.armed;
  // the position now: the latest one moved on by its velocity (it is up to a telemetry period
  // old, more after a frame's processing; at the truck's speed that would put the UAV ahead of
  // it)
  in.position_enu_m = t.position_enu_m;
  if (pose.time_s >= 0) {
    in.position_enu_m +=
        t.velocity_enu_m_s * std::clamp(in.now_s - pose.time_s, 0.0, kMaxExtrapolation_s);
  }
  in.velocity_enu_m_s = t.velocity_enu_m_s;
  in.switch_closed = switch_closed;
  in.camera_dark = camera_dark;
  in.estimate_settling = estimate_settling;
  in.truck = perception.knowledge(in.now_s, in.position_enu_m.head<2>());
  return in;
}

// the FSM's note, a log line for each of its lines
void log_note(const uavsim::mission::ProgramLoop& program, const std::string& note) {
  for (size_t from = 0; from < note.size();) {
    const size_t nl = std::min(note.find('\n', from), note.size());
    program.log(note.substr(from, nl - from));
    from = nl + 1;
  }
}

void log_interception(const uavsim::mission::ProgramLoop& program, const TruckKnowledge& truck) {
  char buf[128];
  std::snprintf(buf, sizeof(buf), "interception point (%.1f, %.1f), %.1f s to go",
                truck.interception_enu_m->x(), truck.interception_enu_m->y(),
                truck.interception_time_to_go_s);
  program.log(buf);
}

void log_first_sighting(const uavsim::mission::ProgramLoop& program, const Eigen::Vector2d& seen,
                        int64_t stamp_us) {
  char buf[128];
  std::snprintf(buf, sizeof(buf), "first sighting: marker at (%.1f, %.1f) in the image of t=%.2f",
                seen.x(), seen.y(), stamp_us * 1e-6);
  program.log(buf);
}

// the vision computer on a frame: vision_latency_s of detached time, the simulation going on
// meanwhile; the first sighting is logged. True when the frame was black (the camera blinded or
// failed: the ground is never this dark)
bool look_at(EventLoop& loop, const MissionConfig& config, const Pending& frame,
             TruckPerception& perception, int reported_detections,
             const uavsim::mission::ProgramLoop& program) {
  std::optional<Eigen::Vector2d> seen;
  bool dark = false;
  loop.run_busy(config.vision_latency_s, [&] {
    seen = perception.on_frame(frame.grey, frame.intrinsics, frame.stamp_us, frame.pose);
    dark = cv::mean(frame.grey)[0] < kDarkFrameMean;
  });
  if (seen && reported_detections == 0) log_first_sighting(program, *seen, frame.stamp_us);
  return dark;
}

void log_touchdown(const uavsim::mission::ProgramLoop& program, const FsmInputs& in) {
  const Eigen::Vector2d off = in.truck.position_enu_m - in.position_enu_m.head<2>();
  char buf[160];
  std::snprintf(buf, sizeof(buf), "touchdown: motors off; the marker estimated at (%+.2f, %+.2f) m",
                off.x(), off.y());
  program.log(buf);
}

}  // namespace

int main(int argc, char** argv) {
  const std::optional<Options> o = parse_options(argc, argv);
  if (!o) return usage();
  const std::string& vehicle = o->vehicle;

  auto started = uavsim::mission::start_vehicle_program(vehicle, o->mavlink);
  if (!started) return 1;
  uavsim::mission::ProgramLoop& program = *started->program;
  EventLoop& loop = program.loop();
  Vehicle& uav = *started->vehicle;

  TimedPose pose;
  // the position's own time (time_boot_ms) on the loop clock: the smallest arrival delay seen is
  // the clock offset (a position arrives up to a telemetry period after it was taken; at 4 m/s a 50
  // ms error would put every marker 0.2 m off)
  double vehicle_clock_offset_s = std::numeric_limits<double>::infinity();
  // steps in the FC's own position estimate (a GPS jump blended in), told from the UAV's motion
  EstimateMonitor estimate_monitor;
  int estimate_steps = 0;
  bool estimate_settling = false;
  // the camera's view of the truck, placed by that estimate (declared here: a step restarts its
  // track)
  const MissionConfig config;
  TruckPerception perception(config);
  uav.on_telemetry([&](const Telemetry& t) {
    if (!t.has_local_position) return;
    estimate_monitor.add(t.vehicle_time_s, t.position_enu_m.head<2>(),
                         t.velocity_enu_m_s.head<2>());
    // a step: the truck's track, made in the estimate's old frame, is set aside; settled: it is
    // made again from the frames taken from now on
    if (estimate_monitor.jumps() > estimate_steps) {
      estimate_steps = estimate_monitor.jumps();
      perception.on_estimate_step();
    }
    if (estimate_settling && !estimate_monitor.settling())
      perception.on_estimate_settled(loop.now());
    estimate_settling = estimate_monitor.settling();
    vehicle_clock_offset_s = std::min(vehicle_clock_offset_s, loop.now() - t.vehicle_time_s);
    pose = {t.vehicle_time_s + vehicle_clock_offset_s, t.position_enu_m, t.velocity_enu_m_s,
            enu_yaw_from_ned(t.yaw_rad)};
  });

  // the camera: the newest frame waits for the vision computer (older ones are skipped, as a
  // pipeline that always takes the latest image)
  std::optional<Pending> pending;
  std::unique_ptr<uavsim::vision::VideoLogWriter> vlog;
  if (!uavsim::mission::open_video_log(program, o->video_log, &vlog)) return 1;
  const auto sub = uavsim::mission::subscribe_camera(program, o->camera, CameraFormat::kGrey,
                                                     [&](const CameraFrame& f) {
                                                       if (pose.time_s < 0 || f.image.empty())
                                                         return;
                                                       pending = pending_frame(f, pose, perception);
                                                     });
  if (!sub) return 1;

  // the landing-pad microswitches
  bool switch_closed = false;
  bool camera_dark = false;  // the newest processed frame was black
  auto switches =
      PadSwitches::subscribe(loop, vehicle, [&](const SwitchState& s) { switch_closed = s.any(); });
  if (!switches) {
    program.log("pad switches: " + switches.message());
    return 1;
  }

  if (!uavsim::mission::wait_vehicle_ready(program, uav, 120)) return 1;
  const double yaw_hold = enu_yaw_from_ned(uav.telemetry().yaw_rad);
  LandingFsm fsm(config);
  program.log("ready: MBZIRC 2017 landing, FSM of seed fig. 7.6");

  double last_step_s = -1e9, landed_s = -1.0;
  int reported_detections = 0;
  bool touchdown_reported = false;
  while (loop.now() < kBudget_s) {
    if (!loop.clock_alive()) {
      program.log("clock lost");
      return 1;
    }
    if (pending) {
      const Pending frame = std::move(*pending);
      pending.reset();
      camera_dark = look_at(loop, config, frame, perception, reported_detections, program);
      reported_detections = perception.detections();
      if (vlog) {
        DrawingContext context;
        context.vehicle = vehicle;
        context.fsm_state = landing_state_name(fsm.state());
        context.detections = perception.detections();
        context.truck = perception.knowledge(loop.now(), uav.telemetry().position_enu_m.head<2>());
        // a full queue drops the frame, never waits
        (void)vlog->submit(detection_log_frame(frame.grey, frame.stamp_us * 1e-6,
                                               perception.last_outcome(), context));
      }
    } else {
      (void)loop.run_until(
          [&] { return pending.has_value() || loop.now() - last_step_s >= kStep_s - 1e-9; },
          kStep_s, "a frame or the next step");
    }
    if (loop.now() - last_step_s < kStep_s - 1e-9 && !switch_closed) continue;
    last_step_s = loop.now();

    const FsmInputs in = fsm_inputs(loop.now(), uav.telemetry(), pose, switch_closed, camera_dark,
                                    estimate_monitor.settling(), perception);
    const LandingState before = fsm.state();
    const FsmOutputs out = fsm.step(in);
    log_note(program, out.note);
    if (fsm.state() == LandingState::kIntercept && before != LandingState::kIntercept &&
        in.truck.interception_enu_m) {
      log_interception(program, in.truck);
    }
    // the heading held throughout
    uavsim::mission::fly(program, uav, out, yaw_hold);
    if (fsm.state() == LandingState::kLanded) {
      if (!touchdown_reported) {
        touchdown_reported = true;
        landed_s = loop.now();
        log_touchdown(program, in);
      }
      if (loop.now() - landed_s > kLinger_s && !uav.telemetry().armed) break;
    }
  }
  program.log(std::string("mission over: ") + landing_state_name(fsm.state()) + ", " +
              std::to_string(perception.detections()) + " marker detections");
  return fsm.state() == LandingState::kLanded ? 0 : 3;
}
