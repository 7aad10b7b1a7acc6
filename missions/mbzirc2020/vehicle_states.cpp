// The balloon UAV's states from Take-off to Back Off (fig. 7.13), one handler each, with the
// transitions that set a state up. Land's phases are in vehicle_landing.cpp.
#include <algorithm>
#include <cmath>
#include <string>

#include "ground_station.hpp"
#include "uavsim/client/geodesy.hpp"
#include "vehicle_fsm.hpp"
#include "vehicle_fsm_tuning.hpp"

namespace uavsim::missions::mbzirc2020 {
namespace {

using client::wrap_pi;
using namespace vehicle_tuning;  // the machine's own constants, unqualified

}  // namespace

void VehicleFsm::on_take_off(const VehicleInputs& in, VehicleOutputs& out) {
  const Eigen::Vector3d& p = in.position_enu_m;
  if (p.z() >= config_.takeoff_altitude_m - 0.3) {
    hold_altitude_m_ = p.z();
    enter(VehicleState::kGoSideCenter, out, fmt("%.1f m reached", p.z()));
  }
}

void VehicleFsm::on_go_side_center(const VehicleInputs& in, VehicleOutputs& out) {
  // "reaches the midpoint of one of the long sides ... maintaining the current altitude. The
  // heading is adjusted so that the camera points towards the inner part of the arena"
  const Eigen::Vector3d& p = in.position_enu_m;
  const Eigen::Vector3d target(0.5 * (config_.arena_x_min_m + config_.arena_x_max_m), line_y_m(),
                               hold_altitude_m_);
  // from a scan line (take-over, re-task) climb over the balloons before crossing the arena
  Eigen::Vector3d goal = target;
  if (p.z() < hold_altitude_m_ - 0.5) goal.head<2>() = p.head<2>();
  out.action = VehicleOutputs::Action::kVelocity;
  out.velocity_enu_m_s = toward(p, goal, config_.transit_speed_m_s);
  out.yaw_enu_rad = inward_yaw_rad();
  if ((target.head<2>() - p.head<2>()).norm() < config_.position_tolerance_m) {
    plan_scan();
    hold_altitude_m_ = scan_[0].altitude_m;
    enter(VehicleState::kGoScanAltitude, out,
          fmt("side centre (%.1f, %.1f)", target.x(), target.y()));
  }
}

void VehicleFsm::on_go_scan_altitude(const VehicleInputs& in, VehicleOutputs& out) {
  const Eigen::Vector3d& p = in.position_enu_m;
  const Eigen::Vector3d target(0.5 * (config_.arena_x_min_m + config_.arena_x_max_m), line_y_m(),
                               hold_altitude_m_);
  out.action = VehicleOutputs::Action::kVelocity;
  out.velocity_enu_m_s = toward(p, target, config_.transit_speed_m_s);
  out.yaw_enu_rad = inward_yaw_rad();
  if (std::abs(p.z() - hold_altitude_m_) < config_.altitude_tolerance_m) {
    enter(VehicleState::kBlindScan, out, fmt("%.2f m", p.z()));
  }
}

void VehicleFsm::on_blind_scan(const VehicleInputs& in, VehicleOutputs& out) {
  // "Whenever a green balloon is detected, a transition to the Area Allocation Request is
  // immediately executed"
  if (auto b = choose_target(in)) {
    request_airspace(in, *b, out);
    return;
  }
  if (scan_leg_ >= scan_.size()) {
    end_of_scan_plan(in, out);
    return;
  }
  const Eigen::Vector3d& p = in.position_enu_m;
  const ScanWaypoint& w = scan_[scan_leg_];
  hold_altitude_m_ = w.altitude_m;
  const Eigen::Vector3d target(w.x_m, line_y_m(), w.altitude_m);
  out.action = VehicleOutputs::Action::kVelocity;
  out.velocity_enu_m_s = toward(p, target, config_.scan_speed_m_s);
  out.yaw_enu_rad = inward_yaw_rad();
  if ((target.head<2>() - p.head<2>()).norm() < config_.position_tolerance_m) {
    ++scan_leg_;
    out.note = fmt("scan waypoint x=%.0f reached", w.x_m);
  }
}

void VehicleFsm::end_of_scan_plan(const VehicleInputs& in, VehicleOutputs& out) {
  if (take_over_ && !other_side_done_) {
    // this side is done; the other UAV's half is still to scan: from the line short of the
    // middle, over the balloons, as a re-tasked UAV does. Not from the far side's line: with
    // the GPS bias (up to 2-3 m) a balloon a few metres in front of that line is seen by
    // neither scan leg (one-UAV field seed 14: two balloons 4.8 and 8.6 m in front of it,
    // the UAV 2.7 m nearer them than it thought); from the middle the camera sees 9-40 m
    // ahead, the whole far half, and the line is 34 m nearer.
    other_side_done_ = true;
    start_crossing(out, "scans done, taking over the other half");
    return;
  }
  if (take_over_ && cross_ && !look_home_) {
    // the UAV alone, both halves scanned and balloons left (the GCS lands it once five are
    // reported): its own half once more, from over the balloons 6 m beyond the middle,
    // looking back at it, one leg from where it is to the other end. One-UAV field seeds 4
    // and 17: a balloon 3.4 / 5.7 m in front of the own line at the height spread's edge
    // (2.20 / 3.17 m), which from so close the camera sees only within a few tenths of a
    // metre of its own height, was missed by both legs there (GPS bias and baro drift move
    // them); from 28 m it lies near the 5 deg down camera's axis.
    look_home_ = true;
    const double x = in.position_enu_m.x();
    const double east = config_.arena_x_max_m - config_.scan_corner_inset_m;
    const double west = config_.arena_x_min_m + config_.scan_corner_inset_m;
    const double end = std::abs(x - east) < std::abs(x - west) ? west : east;
    scan_ = {{x, config_.cross_altitude_m}, {end, config_.cross_altitude_m}};
    scan_leg_ = 0;
    hold_altitude_m_ = config_.cross_altitude_m;
    hover(in, out, in.yaw_enu_rad);
    out.note = "both halves scanned: the own half again, from beyond the middle";
    return;
  }
  if (!take_over_ && !cross_) {
    // balloons may be left (the GCS lands everyone once all five are reported): ask it
    hover(in, out, inward_yaw_rad());
    enter(VehicleState::kScansDone, out, "own scans done: waiting for the GCS");
    return;
  }
  start_landing(out, look_home_ ? "both halves scanned from the middle"
                     : cross_   ? "the other half scanned"
                                : "two full scans done");
}

void VehicleFsm::start_crossing(VehicleOutputs& out, const std::string& why) {
  cross_ = true;
  plan_scan();
  hold_altitude_m_ = config_.cross_altitude_m;
  enter(VehicleState::kGoSideCenter, out, why);
}

void VehicleFsm::on_scans_done(const VehicleInputs& in, VehicleOutputs& out) {
  if (auto b = choose_target(in)) {
    request_airspace(in, *b, out);
    return;
  }
  if (retask_) {
    start_crossing(out, "re-tasked: to the other half, over the balloons");
    return;
  }
  const Eigen::Vector3d& p = in.position_enu_m;
  out.action = VehicleOutputs::Action::kVelocity;
  out.velocity_enu_m_s = toward(p, {p.x(), line_y_m(), hold_altitude_m_}, 0.0);
  out.yaw_enu_rad = inward_yaw_rad();
  if (in.now_s - state_since_s_ > config_.retask_wait_s)
    start_landing(out, "no re-task from the GCS");
}

void VehicleFsm::follow_target(const VehicleInputs& in) {
  for (const BalloonSighting& b : in.balloons) {
    if (b.track_id == target_.track_id ||
        (b.position_enu_m - target_.position_enu_m).norm() < kSameBalloon_m) {
      if (b.last_seen_s >= target_.last_seen_s) target_ = b;
    }
  }
}

std::string VehicleFsm::take_balloon_in_the_way(const VehicleInputs& in) {
  const Eigen::Vector2d p = in.position_enu_m.head<2>();
  const Eigen::Vector2d t = target_.position_enu_m.head<2>();
  const double target_range_m = (t - p).norm();
  for (const BalloonSighting& b : in.balloons) {
    const Eigen::Vector2d q = b.position_enu_m.head<2>();
    if (b.track_id == target_.track_id || in.now_s - b.last_seen_s > kFreshSighting_s ||
        (q - t).norm() < kSameBalloon_m || (q - p).norm() >= target_range_m ||
        segment_distance(p, t, q, q) >= kInTheWay_m) {
      continue;
    }
    bool popped = false;
    for (const Eigen::Vector3d& r : popped_at_)
      popped = popped || (r.head<2>() - q).norm() < kPoppedExclusion_m;
    if (popped) continue;
    target_ = b;
    closest_blade_m_ = 1e9;
    return fmt("balloon in the way at (%.1f, %.1f, %.1f): the target now", q.x(), q.y(),
               b.position_enu_m.z());
  }
  return {};
}

void VehicleFsm::on_area_allocation_request(const VehicleInputs& in, VehicleOutputs& out) {
  const Eigen::Vector3d& p = in.position_enu_m;
  follow_target(in);
  hover(in, out, inward_yaw_rad());
  // from over the balloons (re-tasked), go down to the blades' height while waiting
  if (cross_) {
    out.velocity_enu_m_s = toward(
        p, {p.x(), p.y(), target_.position_enu_m.z() + config_.pierce_blade_above_centre_m}, 0.0);
  }
  bool granted = false;
  for (const auto& r : in.airspace_replies) granted = granted || (r && request_ && *r == *request_);
  if (granted) {
    start_pierce(in, out);
  } else if (in.now_s - target_.last_seen_s > config_.allocation_wait_lost_s) {
    // "should the balloon be no longer visible (e.g. if popped by the other UAV while waiting),
    // the request can be cancelled by sending a NaN position"
    out.airspace = std::optional<AirspaceArea>();
    request_.reset();
    enter(VehicleState::kBlindScan, out, "balloon lost while waiting: request cancelled");
  }
}

void VehicleFsm::start_pierce(const VehicleInputs& in, VehicleOutputs& out) {
  airspace_held_ = true;
  closest_blade_m_ = 1e9;
  pierce_level_camera_ = false;
  coast_dir_ = (target_.position_enu_m.head<2>() - in.position_enu_m.head<2>()).normalized();
  pierce_dir_ = coast_dir_;
  enter(VehicleState::kPierce, out, "airspace granted");
}

void VehicleFsm::on_pierce(const VehicleInputs& in, VehicleOutputs& out) {
  follow_target(in);
  if (std::string note = take_balloon_in_the_way(in); !note.empty()) out.note = note;
  const double along_m = steer_pierce(in, out);
  // "this state is maintained for N seconds after the balloon was last detected" (or until the
  // blades are through it)
  const bool seen = in.now_s - target_.last_seen_s < kFreshSighting_s;
  const bool through = !seen && along_m >= config_.pierce_overshoot_m;
  const bool coasted = in.now_s - target_.last_seen_s > config_.pierce_coast_s;
  const bool timeout = in.now_s - state_since_s_ > config_.pierce_timeout_s;
  const bool turned = coast_dir_.dot(pierce_dir_) < std::cos(kPierceMaxTurn_rad);
  if (!through && !coasted && !timeout && !turned) return;
  // the camera cannot tell a pop (it lost the balloon at close range, or the blades passed its
  // estimate unseen, maybe beside it): if the blades got there, look back at it while backing off;
  // POPPED is reported only if it is not seen again
  pierce_reached_ = closest_blade_m_ < 0.35 || along_m > -0.2;
  seen_again_ = false;
  look_back_since_s_ = -1.0;
  hold_altitude_m_ =
      scan_leg_ < scan_.size() ? scan_[scan_leg_].altitude_m : scan_.back().altitude_m;
  pierce_start_enu_m_.z() = hold_altitude_m_;
  enter(VehicleState::kBackOff, out,
        std::string(through   ? "through the balloon"
                    : timeout ? "timeout"
                    : turned  ? "the target turned away"
                              : "balloon lost") +
            (pierce_reached_ ? ", blades reached it" : ", blades did not reach it"));
}

double VehicleFsm::steer_pierce(const VehicleInputs& in, VehicleOutputs& out) {
  // "moves forward, while adjusting its lateral and vertical position so that the balloon stays
  // horizontally centred and at the same height as the strip of blades"
  const Eigen::Vector3d& p = in.position_enu_m;
  const Eigen::Vector3d& b = target_.position_enu_m;
  const Eigen::Vector2d heading(std::cos(in.yaw_enu_rad), std::sin(in.yaw_enu_rad));
  const Eigen::Vector2d blade_xy = p.head<2>() + config_.blade_offset_body_m.x() * heading;
  const double blade_range = (b.head<2>() - blade_xy).norm();
  closest_blade_m_ = std::min(closest_blade_m_, blade_range);
  const bool seen = in.now_s - target_.last_seen_s < kFreshSighting_s;
  // the blades ride just above the balloon's centre as the camera sees it: the balloon's height
  // and ours come from the same estimate, so its bias (a metre of GPS / baro error in the
  // field) cancels; the rules' heights would not (the pole top is 0.28 m below the centre)
  double blade_z = std::clamp(b.z() + config_.pierce_blade_above_centre_m,
                              p.z() - kMaxPierceClimb_m, p.z() + kMaxPierceClimb_m);
  for (const Eigen::Vector3d& q : popped_at_) {
    if (segment_distance(p.head<2>(), b.head<2>(), q.head<2>(), q.head<2>()) < kPoleClearance_m)
      blade_z = std::max(blade_z, q.z() + config_.backoff_above_centre_m);
  }
  double speed = config_.pierce_speed_near_m_s;
  if (seen) {
    coast_dir_ = (b.head<2>() - p.head<2>()).normalized();
    const double s = std::clamp((blade_range - 1.0) / config_.pierce_slow_range_m, 0.0, 1.0);
    speed = config_.pierce_speed_near_m_s +
            s * (config_.pierce_speed_far_m_s - config_.pierce_speed_near_m_s);
    const double yaw_error = wrap_pi(std::atan2(coast_dir_.y(), coast_dir_.x()) - in.yaw_enu_rad);
    if (std::abs(yaw_error) > 0.35) speed *= 0.3;  // turn towards it first: the camera must keep it
  }
  // and reach blade height before the balloon is close (from the high scan altitude it is 0.5 m
  // down)
  const double dz = std::abs(blade_z - p.z());
  if (blade_range < 2.0 * config_.pierce_slow_range_m)
    speed *= std::clamp(1.0 - (dz - 0.1) / 0.3, 0.15, 1.0);
  if (dz > 0.6) speed = 0.0;  // far above or below (re-tasked, over the balloons): height first
  // the camera levels once the blades are at the balloon's height (then the balloon is on the
  // optical axis and stays in view up to ~1.4 m; 5 deg down it would leave at ~2.7 m)
  pierce_level_camera_ = pierce_level_camera_ || dz < 0.3;
  out.camera_pitch_rad = pierce_level_camera_ ? 0.0 : config_.camera_pitch_rad;
  const double along_m = (blade_xy - b.head<2>()).dot(coast_dir_);  // > 0: blades past the centre
  // once the blades are at the balloon's near side, climb: the hull passes over the pole
  // 0.43 m after the blades pass the centre, and the pole top is only 0.36 m under the blades
  // (field seed 10, one UAV: the hull on the pole 0.27 s after the pop, the balloon's height
  // seen 0.2 m low)
  const double exit_climb_m_s =
      along_m > -config_.pierce_exit_climb_from_m ? config_.pierce_exit_climb_m_s : 0.0;
  out.action = VehicleOutputs::Action::kVelocity;
  out.velocity_enu_m_s = {coast_dir_.x() * speed, coast_dir_.y() * speed,
                          std::clamp(kGainZ_1_s * (blade_z - p.z()) + exit_climb_m_s,
                                     -config_.max_climb_m_s, config_.max_climb_m_s)};
  out.yaw_enu_rad = std::atan2(coast_dir_.y(), coast_dir_.x());
  return along_m;
}

void VehicleFsm::on_back_off(const VehicleInputs& in, VehicleOutputs& out) {
  // "the UAV moves backwards in order to resume the Blind Scan operation and deallocates the
  // area"; backwards indeed: the camera keeps looking where the balloon was
  const Eigen::Vector3d& p = in.position_enu_m;
  const Eigen::Vector3d& b = target_.position_enu_m;
  for (const BalloonSighting& s : in.balloons) {
    if (in.now_s - s.last_seen_s < kFreshSighting_s && s.last_seen_s > state_since_s_ + 0.5 &&
        (s.position_enu_m - b).norm() < kSeenAgain_m) {
      seen_again_ = true;
    }
  }
  const Eigen::Vector2d to_b = b.head<2>() - p.head<2>();
  const Eigen::Vector3d goal = back_off_goal(p);
  out.action = VehicleOutputs::Action::kVelocity;
  out.velocity_enu_m_s = toward(p, goal, config_.transit_speed_m_s);
  // the camera towards where the balloon was, so that one still there is seen again; but not
  // within a few metres, where the heading to it swings round when the pierce passed it close
  // by (there: hold the heading). Field seed 8: holding the pierce's heading all the way back
  // left a balloon the blades had passed 0.7 m beside 40 deg out of view, and it was reported
  // popped.
  out.yaw_enu_rad =
      to_b.norm() > kBackOffFaceBalloon_m ? std::atan2(to_b.y(), to_b.x()) : in.yaw_enu_rad;
  const bool back =
      (pierce_start_enu_m_.head<2>() - p.head<2>()).norm() < config_.position_tolerance_m;
  if (back && pierce_reached_ && !seen_again_) {
    if (look_back_since_s_ < 0.0) look_back_since_s_ = in.now_s;
    if (in.now_s - look_back_since_s_ < kLookBack_s) {
      hover(in, out, std::atan2(to_b.y(), to_b.x()));
      out.velocity_enu_m_s = toward(p, goal, config_.transit_speed_m_s);
      return;
    }
  }
  if (back) end_back_off(out);
}

Eigen::Vector3d VehicleFsm::back_off_goal(const Eigen::Vector3d& p) const {
  // near the pole, first climb in place to clear its top (0.28 m under the balloon's centre as
  // the camera saw it: relative, so the estimator's height bias cancels), then go back over it;
  // the scan altitude is a height in the estimator's frame and may lie a metre lower in truth
  // Back over the arena above every pole: the scan line has none, but the way back to it may
  // cross the pole of a balloon popped earlier (one-UAV field seed 12: back from its second
  // balloon at the low leg's height, a propeller met the pole of the first, 12 m behind it).
  const Eigen::Vector3d& b = target_.position_enu_m;
  Eigen::Vector3d goal = pierce_start_enu_m_;
  goal.z() = std::max(goal.z(), config_.backoff_altitude_m);
  if ((b.head<2>() - p.head<2>()).norm() < config_.backoff_pole_clearance_m) {
    const double clear_z = b.z() + config_.backoff_above_centre_m;
    goal.z() = std::max(goal.z(), clear_z);
    if (p.z() < clear_z - 0.15) goal.head<2>() = p.head<2>();
  }
  return goal;
}

void VehicleFsm::end_back_off(VehicleOutputs& out) {
  out.airspace = std::optional<AirspaceArea>();
  airspace_held_ = false;
  request_.reset();
  std::string why = "back on the scan line: airspace released";
  if (pierce_reached_ && !seen_again_) {
    const Eigen::Vector2d b = target_.position_enu_m.head<2>();
    ++popped_;
    popped_at_.push_back(target_.position_enu_m);
    out.popped_enu_m = b;
    why += ", balloon gone (" + std::to_string(popped_) + " popped)";
  } else {
    why += seen_again_ ? ", the balloon is still there" : "";
  }
  enter(VehicleState::kBlindScan, out, why);
}

}  // namespace uavsim::missions::mbzirc2020
