// The UAV's view of the truck (seed 7.1): the landing-marker detector on each grey frame of the
// down-looking camera, the camera pose from the vehicle's own telemetry and its stabilised gimbal,
// the marker's position on the deck plane (height known from the rules, distance from the GPS
// altitude), and the Kalman filter on arc length and lateral offset with delayed measurements,
// whose extrapolation gives the truck now and the best interception point. Pure: frames and poses
// in, knowledge out.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <limits>
#include <opencv2/core.hpp>
#include <optional>

#include "landing_fsm.hpp"
#include "mission_config.hpp"
#include "uavsim/vision/camera_model.hpp"
#include "uavsim/vision/marker_detector.hpp"
#include "uavsim/vision/track_kalman.hpp"

namespace uavsim::missions::mbzirc2017 {

// What one frame gave: the detector's best candidate, and what became of it.
struct FrameOutcome {
  enum class Kind {
    kNoMarker,    // the detector found nothing
    kOffTheDeck,  // a marker in the image whose ray never meets the deck plane (camera above it?)
    kRejected,    // placed on the deck, but the filter's gate refused it (far from the track)
    kAccepted,    // placed on the deck and fed to the filter
    kSettling,    // taken while the UAV's own position estimate settled after a step: not used
  };
  Kind kind = Kind::kNoMarker;
  std::optional<vision::MarkerDetection> detection;
  std::optional<Eigen::Vector2d> deck_enu_m;  // where it was placed (kRejected, kAccepted)
};

const char* frame_outcome_name(FrameOutcome::Kind kind);

class TruckPerception {
 public:
  explicit TruckPerception(const MissionConfig& config);

  // The pose of the down-looking camera, stabilised (roll and pitch cancelled), image top towards
  // the vehicle's heading yaw_enu_rad, on a vehicle whose body origin is at position_enu_m.
  vision::CameraPose camera_pose(const Eigen::Vector3d& position_enu_m, double yaw_enu_rad) const;

  // (frame, intrinsics, the image's stamp, camera pose at the stamp) => the marker's position on
  // the deck if found (and fed to the filter, tied to the image's stamp).
  std::optional<Eigen::Vector2d> on_frame(const cv::Mat& grey,
                                          const vision::PinholeIntrinsics& intrinsics,
                                          int64_t stamp_us, const vision::CameraPose& pose);

  // What is known at now_s (the filter extrapolated; the interception from uav_xy at cruise speed).
  // While the track is being made again after a step (below), the track from before it, marked
  // position_stale: its velocity holds, its position does not.
  TruckKnowledge knowledge(double now_s, const Eigen::Vector2d& uav_xy_enu_m) const;

  // The UAV's own position estimate stepped (estimate_monitor.hpp). Every marker position is the
  // UAV's position plus what the camera saw, so the track made before the step is in the old
  // frame: against the position after it, it puts the truck up to the step's size off (issue 36's
  // seed 172: ~2 m, a blind descent onto the cab's corner). The track is set aside (its velocity
  // still serves), and frames are not used until on_estimate_settled().
  void on_estimate_step();
  // The estimate has settled at now_s: the track is made again from frames taken from then on.
  void on_estimate_settled(double now_s);
  // Whether the track is being made again after a step (from the step until the new track has
  // started).
  bool rebuilding() const { return pre_step_filter_.has_value(); }

  // What the last on_frame() call saw (for a video log's drawings).
  const FrameOutcome& last_outcome() const { return last_; }

  int detections() const { return detections_; }
  int rejected() const { return rejected_; }

 private:
  MissionConfig config_;
  vision::MarkerDetector detector_;
  vision::EightTrack track_;
  vision::TrackKalman filter_;
  // the track from before a step of the UAV's estimate, while the new one starts; and the frames'
  // earliest stamp the new one takes (infinite while the estimate settles)
  std::optional<vision::TrackKalman> pre_step_filter_;
  int64_t use_frames_from_us_ = std::numeric_limits<int64_t>::min();
  FrameOutcome last_;
  double last_seen_s_ = -1e18;
  int detections_ = 0;
  int rejected_ = 0;
};

}  // namespace uavsim::missions::mbzirc2017
