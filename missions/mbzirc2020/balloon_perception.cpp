#include "balloon_perception.hpp"

#include <Eigen/Geometry>
#include <cmath>

namespace uavsim::missions::mbzirc2020 {
namespace {

constexpr double kMinBalloonHeight_m =
    1.2;  // a "balloon" below this is something green on the ground
constexpr double kMaxBalloonHeight_m = 4.5;
// a 5 deg step of the field's gimbal (tau 50 ms, 180 deg/s, 1000 deg/s^2) is within 0.1 deg after
// ~0.25 s; the command reaches it within a tick
constexpr double kGimbalSettle_s = 0.35;
// gimbal reports kept for the frames still to come: the camera's latency (60 ms in the field) and a
// loaded machine's queue are well within
constexpr double kGimbalReportsKept_s = 1.0;

vision::BalloonTrackerParams tracker_params() {
  vision::BalloonTrackerParams p;
  p.confirm_hits = 3;
  p.max_misses = 4;
  // far away the range from the apparent diameter is coarse (a pixel of radius is ~10% at 30 m): a
  // wide gate keeps one track per balloon; balloons are at least 5 m apart
  p.gate_m = 3.0;
  p.lowpass_tau_s = 0.3;
  return p;
}

}  // namespace

BalloonPerception::BalloonPerception(const MissionConfig& config)
    : config_(config), tracker_(tracker_params()) {}

vision::CameraPose BalloonPerception::camera_pose(const Eigen::Vector3d& position_enu_m,
                                                  double yaw_enu_rad, double pitch_rad) const {
  const Eigen::Quaterniond q_enu_body = vision::q_enu_body_from_rpy(0.0, 0.0, yaw_enu_rad);
  return vision::camera_pose_from_vehicle(position_enu_m, q_enu_body,
                                          vision::GimbalAngles{pitch_rad, 0.0, true},
                                          config_.camera_offset_body_m);
}

vision::CameraPose BalloonPerception::camera_pose(const Eigen::Vector3d& position_enu_m,
                                                  double yaw_enu_rad,
                                                  const GimbalReport& gimbal) const {
  vision::CameraPose pose = camera_pose(position_enu_m, yaw_enu_rad, 0.0);
  // MAVLink's FRD angles on our FLU mount: pitch up is a negative turn about y, a clockwise yaw a
  // negative turn about z
  const Eigen::Quaterniond q_enu_mount =
      vision::q_enu_body_from_rpy(gimbal.roll_rad, -gimbal.pitch_rad, yaw_enu_rad - gimbal.yaw_rad);
  pose.R_enu_cam = q_enu_mount.toRotationMatrix() * vision::R_mount_cam();
  return pose;
}

void GimbalReports::add(const GimbalReport& report) {
  if (!reports_.empty() && report.time_s <= reports_.back().time_s) return;
  reports_.push_back(report);
  while (reports_.front().time_s < report.time_s - kGimbalReportsKept_s) reports_.pop_front();
}

std::optional<GimbalReport> GimbalReports::at(double stamp_s, double max_age_s) const {
  for (auto it = reports_.rbegin(); it != reports_.rend(); ++it) {
    if (it->time_s > stamp_s) continue;
    if (it->time_s < stamp_s - max_age_s) return std::nullopt;
    return *it;
  }
  return std::nullopt;
}

void BalloonPerception::set_camera_pitch(double pitch_rad, double since_s) {
  previous_pitch_rad_ = pitch_rad_;
  pitch_rad_ = pitch_rad;
  pitch_since_s_ = since_s;
}

std::optional<double> BalloonPerception::camera_pitch_at(double stamp_s) const {
  if (stamp_s < pitch_since_s_) return previous_pitch_rad_;
  if (stamp_s < pitch_since_s_ + kGimbalSettle_s) return std::nullopt;
  return pitch_rad_;
}

int BalloonPerception::on_frame(const cv::Mat& bgr, const vision::PinholeIntrinsics& intrinsics,
                                double stamp_s, const vision::CameraPose& pose) {
  if (!detector_ || intrinsics.width_px != intrinsics_.width_px ||
      intrinsics.height_px != intrinsics_.height_px || intrinsics.fx_px != intrinsics_.fx_px) {
    intrinsics_ = intrinsics;
    detector_ =
        std::make_unique<vision::BalloonDetector>(vision::BalloonDetectorParams{}, intrinsics_);
  }
  // (image) => balloon centres in the camera frame => in the field frame
  std::vector<Eigen::Vector3d> positions_enu_m;
  last_detections_.clear();
  for (const vision::BalloonDetection& d : detector_->detect(bgr)) {
    const Eigen::Vector3d p = pose.cam_to_enu(d.position_cam_m);
    if (p.z() < kMinBalloonHeight_m || p.z() > kMaxBalloonHeight_m) continue;
    positions_enu_m.push_back(p);
    last_detections_.push_back(d);
  }
  const int64_t stamp_us = static_cast<int64_t>(std::llround(stamp_s * 1e6));
  for (const vision::BalloonTrack& t : tracker_.update(stamp_us, positions_enu_m)) {
    seen_[t.id] = BalloonSighting{t.id, t.position_m, stamp_s};
  }
  // forget the tracks the filter dropped
  for (auto it = seen_.begin(); it != seen_.end();) {
    bool live = false;
    for (const vision::BalloonTrack& t : tracker_.tracks()) live = live || t.id == it->first;
    it = live ? std::next(it) : seen_.erase(it);
  }
  return static_cast<int>(positions_enu_m.size());
}

std::vector<BalloonSighting> BalloonPerception::sightings() const {
  std::vector<BalloonSighting> out;
  for (const auto& [id, s] : seen_) out.push_back(s);
  return out;
}

}  // namespace uavsim::missions::mbzirc2020
