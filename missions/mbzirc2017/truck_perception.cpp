#include "truck_perception.hpp"

#include <cmath>

#include "uavsim/common/angles.hpp"

namespace uavsim::missions::mbzirc2017 {

namespace {
constexpr double kInterceptHorizon_s = 120.0;

int64_t to_us(double t_s) { return static_cast<int64_t>(std::llround(t_s * 1e6)); }
}  // namespace

const char* frame_outcome_name(FrameOutcome::Kind kind) {
  switch (kind) {
    case FrameOutcome::Kind::kNoMarker:
      return "no marker";
    case FrameOutcome::Kind::kOffTheDeck:
      return "off the deck";
    case FrameOutcome::Kind::kRejected:
      return "rejected";
    case FrameOutcome::Kind::kAccepted:
      return "accepted";
    case FrameOutcome::Kind::kSettling:
      return "estimate settling";
  }
  return "?";
}

TruckPerception::TruckPerception(const MissionConfig& config)
    : config_(config), track_(config.track), filter_(track_) {}

vision::CameraPose TruckPerception::camera_pose(const Eigen::Vector3d& position_enu_m,
                                                double yaw_enu_rad) const {
  // the gimbal cancels roll and pitch: only the heading turns the image; straight down, image top
  // forward (models/worlds/mbzirc2017.xml)
  vision::GimbalAngles down;
  down.pitch_rad = -0.5 * common::kPi;
  down.earth_stabilised = true;
  return vision::camera_pose_from_vehicle(position_enu_m,
                                          vision::q_enu_body_from_rpy(0.0, 0.0, yaw_enu_rad), down,
                                          config_.camera_offset_body_m);
}

std::optional<Eigen::Vector2d> TruckPerception::on_frame(
    const cv::Mat& grey, const vision::PinholeIntrinsics& intrinsics, int64_t stamp_us,
    const vision::CameraPose& pose) {
  last_ = FrameOutcome{};
  const std::optional<vision::MarkerDetection> d = detector_.detect(grey);
  if (!d) return std::nullopt;
  last_.detection = d;
  last_.kind = FrameOutcome::Kind::kOffTheDeck;
  const std::optional<Eigen::Vector3d> p =
      vision::marker_position_enu(*d, intrinsics, pose, config_.deck_height_m);
  if (!p) return std::nullopt;
  last_.deck_enu_m = p->head<2>();
  // placed from a position estimate that was still settling after a step: in neither frame
  if (stamp_us < use_frames_from_us_) {
    last_.kind = FrameOutcome::Kind::kSettling;
    return std::nullopt;
  }
  const vision::MeasurementResult r = filter_.add_measurement(stamp_us, p->head<2>());
  if (r == vision::MeasurementResult::kRejected) {
    last_.kind = FrameOutcome::Kind::kRejected;
    ++rejected_;
    return std::nullopt;
  }
  last_.kind = FrameOutcome::Kind::kAccepted;
  ++detections_;
  last_seen_s_ = std::max(last_seen_s_, stamp_us * 1e-6);
  // the new track has started: the one from before the step is done with
  if (filter_.initialised()) pre_step_filter_.reset();
  return p->head<2>();
}

void TruckPerception::on_estimate_step() {
  // a second step before the new track started: the oldest track's velocity still holds, and what
  // the new one took since the first is in yet another frame
  if (!pre_step_filter_ && filter_.initialised()) pre_step_filter_ = filter_;
  filter_.reset();
  last_seen_s_ = -1e18;
  use_frames_from_us_ = std::numeric_limits<int64_t>::max();
}

void TruckPerception::on_estimate_settled(double now_s) { use_frames_from_us_ = to_us(now_s); }

TruckKnowledge TruckPerception::knowledge(double now_s, const Eigen::Vector2d& uav_xy_enu_m) const {
  TruckKnowledge k;
  k.last_seen_s = last_seen_s_;
  const vision::TrackKalman& filter = pre_step_filter_ ? *pre_step_filter_ : filter_;
  const std::optional<vision::TrackEstimate> e = filter.estimate_at(to_us(now_s));
  if (!e) return k;
  k.initialised = true;
  k.position_stale = pre_step_filter_.has_value();
  k.position_enu_m = e->position_enu_m;
  k.velocity_enu_m_s = e->velocity_enu_m_s;
  // the truck drives forward along the track: its heading is the tangent by the sign of its way,
  // its yaw rate the speed times the curvature
  const Eigen::Vector2d tangent = track_.tangent_enu(e->s_m) * (e->v_s_m_s < 0.0 ? -1.0 : 1.0);
  k.heading_enu_rad = std::atan2(tangent.y(), tangent.x());
  k.yaw_rate_rad_s = e->v_s_m_s * track_.curvature_1_m(e->s_m);
  if (const auto i = filter.intercept(to_us(now_s), uav_xy_enu_m, config_.cruise_speed_m_s,
                                      kInterceptHorizon_s)) {
    k.interception_enu_m = i->point_enu_m;
    k.interception_time_to_go_s = i->time_to_go_s;
  }
  return k;
}

}  // namespace uavsim::missions::mbzirc2017
