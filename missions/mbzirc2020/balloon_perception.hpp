// The UAV's balloon pipeline (seed 7.2): detector (colour filter, circle fit, Circle Hough
// refinement, 3D position from the known diameter) on each camera frame, the camera pose from the
// vehicle's own telemetry and its stabilised forward gimbal's reports, and a temporal filter in the
// field frame. Pure: frames and poses in, sightings out.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <opencv2/core.hpp>
#include <optional>
#include <vector>

#include "mission_config.hpp"
#include "uavsim/vision/balloon_detector.hpp"
#include "uavsim/vision/camera_model.hpp"
#include "vehicle_fsm.hpp"

namespace uavsim::missions::mbzirc2020 {

// The camera's attitude as its gimbal device reports it (GIMBAL_DEVICE_ATTITUDE_STATUS in the
// vehicle frame: client::Telemetry's gimbal_attitude_*), at time_s on the vehicle's clock.
// MAVLink's signs: pitch up, yaw clockwise relative to the vehicle's heading, roll right side down.
struct GimbalReport {
  double time_s = -1.0;
  double roll_rad = 0.0, pitch_rad = 0.0, yaw_rad = 0.0;
};

// The gimbal's recent reports, so that a frame is placed with the one of its exposure.
class GimbalReports {
 public:
  // A report, in time order (one no newer than the last is dropped).
  void add(const GimbalReport& report);
  // The last report at or before stamp_s (the closest not after it); nullopt when there is none
  // within max_age_s before it (the reports stopped, or the frame is older than those kept).
  std::optional<GimbalReport> at(double stamp_s, double max_age_s) const;

 private:
  std::deque<GimbalReport> reports_;  // the last second or so
};

class BalloonPerception {
 public:
  explicit BalloonPerception(const MissionConfig& config);

  // The camera pose of the forward-looking stabilised gimbal (at the config's elevation) on a
  // vehicle at position_enu_m with heading yaw_enu_rad (roll and pitch are cancelled by the gimbal;
  // the mount offset is a few centimetres, so the vehicle's tilt moving it is neglected).
  vision::CameraPose camera_pose(const Eigen::Vector3d& position_enu_m, double yaw_enu_rad,
                                 double pitch_rad) const;

  // The camera pose from the gimbal's report (the camera's measured attitude relative to the
  // horizon and to the heading) and the vehicle's telemetry: its position (the balloon's place then
  // shares our own GPS / baro error, which cancels) and its heading as the autopilot estimates it.
  // Neither the commanded elevation nor the frame's own pose: the field gimbal's 50 ms loop lags
  // the body's pitching by several degrees (one-UAV field seed 14: the camera 6 deg above the
  // commanded level while braking, the balloon at 4 m placed 0.4 m low, the pierce flown under it
  // until it left the image's top edge; a propeller then hit it), and the frame's pose is the
  // simulator's ground truth, which a drone does not have. The heading carries the compass's error
  // (a few degrees in the field): the balloon is placed that much off its bearing, which shrinks
  // with the range as the pierce closes in.
  vision::CameraPose camera_pose(const Eigen::Vector3d& position_enu_m, double yaw_enu_rad,
                                 const GimbalReport& gimbal) const;

  // The gimbal was told at loop time since_s to look at this elevation (it was level before the
  // first call). A frame exposed before since_s was taken at the old one; one exposed while the
  // gimbal slews (kGimbalSettle_s) has no known pitch.
  void set_camera_pitch(double pitch_rad, double since_s);
  std::optional<double> camera_pitch_at(double stamp_s) const;

  // (frame, its intrinsics, stamp, camera pose at the stamp) => tracks updated. Returns the
  // detections' count in this frame.
  int on_frame(const cv::Mat& bgr, const vision::PinholeIntrinsics& intrinsics, double stamp_s,
               const vision::CameraPose& pose);

  // Confirmed balloons still tracked, with the time they were last seen.
  std::vector<BalloonSighting> sightings() const;

  // The last frame's detections that passed the height check (for a video log's drawings).
  const std::vector<vision::BalloonDetection>& last_detections() const { return last_detections_; }

 private:
  MissionConfig config_;
  std::unique_ptr<vision::BalloonDetector> detector_;
  vision::PinholeIntrinsics intrinsics_;
  vision::BalloonTracker tracker_;
  std::map<int, BalloonSighting> seen_;  // by track id
  double pitch_rad_ = 0.0, previous_pitch_rad_ = 0.0;
  double pitch_since_s_ = -1e9;
  std::vector<vision::BalloonDetection> last_detections_;
};

}  // namespace uavsim::missions::mbzirc2020
