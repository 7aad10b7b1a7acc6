// The UAV's balloon pipeline (seed 7.2): detector (colour filter, circle fit, Circle Hough
// refinement, 3D position from the known diameter) on each camera frame, the camera pose from the
// vehicle's own telemetry and its stabilised forward gimbal, and a temporal filter in the field
// frame. Pure: frames and poses in, sightings out.
#pragma once

#include <Eigen/Core>
#include <cstdint>
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

class BalloonPerception {
 public:
  explicit BalloonPerception(const MissionConfig& config);

  // The camera pose of the forward-looking stabilised gimbal (at the config's elevation) on a
  // vehicle at position_enu_m with heading yaw_enu_rad (roll and pitch are cancelled by the gimbal;
  // the mount offset is a few centimetres, so the vehicle's tilt moving it is neglected).
  vision::CameraPose camera_pose(const Eigen::Vector3d& position_enu_m, double yaw_enu_rad,
                                 double pitch_rad) const;

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
