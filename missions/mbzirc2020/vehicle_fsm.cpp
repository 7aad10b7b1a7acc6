#include "vehicle_fsm.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "uavsim/client/geodesy.hpp"
#include "uavsim/common/angles.hpp"

namespace uavsim::missions::mbzirc2020 {
namespace {

using client::wrap_pi;
using common::kPi;
constexpr double kGainXy_1_s = 1.0;       // position error -> horizontal speed
constexpr double kGainZ_1_s = 1.5;        // altitude error -> climb rate
constexpr double kFreshSighting_s = 0.5;  // a sighting older than this is "lost"
constexpr double kSameBalloon_m = 1.5;    // a new track this close to the target is the target
constexpr double kPoppedExclusion_m = 2.5;
constexpr double kArenaMargin_m = 0.5;
// a balloon seen further above or below is a bad estimate
constexpr double kMaxPierceClimb_m = 1.5;
// The heading setpoint turns at most this fast. The flight controller's mixer keeps yaw torque
// before collective thrust (ArduCopter keeps some thrust headroom first): a setpoint that jumps by
// 90-180 deg saturates it and the vehicle sinks. Field seed 20 (two UAVs): backing off past a
// balloon it had missed by 1.6 m, the heading to the balloon swung through 140 deg in 3 s; the UAV
// sank from 3.4 m into the ground at 3.1 m/s while commanded to climb.
constexpr double kMaxYawRate_rad_s = 1.0;
constexpr double kBackOffFaceBalloon_m = 3.0;
// A pierce whose target has turned further than this from where it pointed at the start is not
// going through that balloon: one-UAV field seed 6 turned through 130 deg towards another balloon
// 6.7 m away as the target's track drifted at close range (a balloon cut by the image's edge reads
// too far), and met that balloon's pole.
constexpr double kPierceMaxTurn_rad = 60.0 * kPi / 180.0;
// the landing spot is approached so that the vehicle can stop there at this deceleration; the
// descent starts only once it is (almost) still: braking from 5-6 m/s while descending, the
// controller's vertical loop gave way (one-UAV field seeds 8 and 9: 2.7 m/s sink from 4.5 m, roll
// 19 deg)
constexpr double kLandingApproachDecel_m_s2 = 1.5;
constexpr double kLandingStillSpeed_m_s = 0.5;
constexpr double kLandingPauseClimb_m_s = 0.3;  // the last 2 m paused for a gust (touchdown_gate)
// over the spot, the lean is read this long before the heading turns the skids along the wind,
// and the descent starts once they are within kLandingSkidAlign_rad of it (or after
// kLandingAlignMax_s whatever the heading)
constexpr double kLandingWindRead_s = 2.0;
constexpr double kLandingSkidAlign_rad = 10.0 * kPi / 180.0;
constexpr double kLandingAlignMax_s = 10.0;
// A pierce that ended without the blades going through (the camera lost the balloon at close
// range) reports POPPED only after this long back on the line facing where the balloon was, a
// sighting within kSeenAgain_m of it meaning it is still there. Two-UAV field seeds 2 and 5: the
// balloon, 4 m in front of the line and 3.0-3.1 m high, seen 0.8-1.1 m from where it was; the
// blades reached the estimate, not the balloon; the back off climbed over it (out of the 5 deg
// down camera's view within 3 m) and was over in 2 s, and the balloon was reported popped, its
// true place then excluded from targets as a popped balloon's.
constexpr double kLookBack_s = 2.5;
constexpr double kSeenAgain_m = 2.0;

std::string fmt(const char* f, double a = 0, double b = 0, double c = 0) {
  char buf[160];
  std::snprintf(buf, sizeof(buf), f, a, b, c);
  return buf;
}

}  // namespace

const char* vehicle_state_name(VehicleState s) {
  switch (s) {
    case VehicleState::kPreflight:
      return "Preflight";
    case VehicleState::kTakeOff:
      return "Take-off";
    case VehicleState::kGoSideCenter:
      return "Go Side Center";
    case VehicleState::kGoScanAltitude:
      return "Go Scan Altitude";
    case VehicleState::kBlindScan:
      return "Blind Scan";
    case VehicleState::kAreaAllocationRequest:
      return "Area Allocation Request";
    case VehicleState::kPierce:
      return "Pierce";
    case VehicleState::kBackOff:
      return "Back Off";
    case VehicleState::kLand:
      return "Land";
    case VehicleState::kLanded:
      return "Landed";
    case VehicleState::kFailed:
      return "Failed";
    case VehicleState::kScansDone:
      return "Scans Done";
  }
  return "?";
}

VehicleFsm::VehicleFsm(const MissionConfig& config, int index, Side side,
                       const Eigen::Vector2d& landing_spot_enu_m)
    : config_(config),
      index_(index),
      side_(side),
      home_side_(side),
      landing_spot_enu_m_(landing_spot_enu_m) {}

double VehicleFsm::line_y_m() const {
  if (cross_) {
    const double mid_y = 0.5 * (config_.arena_y_min_m + config_.arena_y_max_m);
    const bool south_of_middle = (home_side_ == Side::kSouth) != look_home_;
    return south_of_middle ? mid_y - config_.cross_line_back_m : mid_y + config_.cross_line_back_m;
  }
  return side_ == Side::kSouth ? config_.arena_y_min_m + config_.side_inset_m
                               : config_.arena_y_max_m - config_.side_inset_m;
}

double VehicleFsm::inward_yaw_rad() const {
  return (side_ == Side::kSouth) != look_home_ ? kPi / 2 : -kPi / 2;
}

bool VehicleFsm::in_own_half(const Eigen::Vector3d& p) const {
  if (take_over_ || cross_) return true;
  const double mid_y = 0.5 * (config_.arena_y_min_m + config_.arena_y_max_m);
  return home_side_ == Side::kSouth ? p.y() <= mid_y + config_.own_half_margin_m
                                    : p.y() >= mid_y - config_.own_half_margin_m;
}

// seed: "the UAV slowly translates sideways ... When a corner of the arena rectangle is reached,
// the direction of the translation is inverted and the operating altitude is swapped ... After two
// full scans the UAV, which is back at the midpoint, transitions to the Land state". S0 sweeps east
// first, S1 west first, so the two start on different balloons.
void VehicleFsm::plan_scan() {
  const double centre_x = 0.5 * (config_.arena_x_min_m + config_.arena_x_max_m);
  const double east = config_.arena_x_max_m - config_.scan_corner_inset_m;
  const double west = config_.arena_x_min_m + config_.scan_corner_inset_m;
  const double first = index_ == 0 ? east : west, second = index_ == 0 ? west : east;
  const double a = index_ == 0 ? config_.scan_altitude_low_m : config_.scan_altitude_high_m;
  const double b = index_ == 0 ? config_.scan_altitude_high_m : config_.scan_altitude_low_m;
  scan_ = {{first, a}, {second, b}, {centre_x, a}};
  // re-tasked: one sweep each way over the balloons, looking at the other half
  if (cross_) scan_ = {{first, config_.cross_altitude_m}, {second, config_.cross_altitude_m}};
  scan_leg_ = 0;
}

Eigen::Vector3d VehicleFsm::toward(const Eigen::Vector3d& p, const Eigen::Vector3d& target,
                                   double max_speed_m_s) const {
  Eigen::Vector2d v_xy = kGainXy_1_s * (target.head<2>() - p.head<2>());
  if (v_xy.norm() > max_speed_m_s) v_xy *= max_speed_m_s / v_xy.norm();
  const double vz =
      std::clamp(kGainZ_1_s * (target.z() - p.z()), -config_.max_climb_m_s, config_.max_climb_m_s);
  return {v_xy.x(), v_xy.y(), vz};
}

void VehicleFsm::hover(const VehicleInputs& in, VehicleOutputs& out, double yaw_enu_rad) const {
  out.action = VehicleOutputs::Action::kVelocity;
  out.velocity_enu_m_s = toward(
      in.position_enu_m, {in.position_enu_m.x(), in.position_enu_m.y(), hold_altitude_m_}, 0.0);
  out.yaw_enu_rad = yaw_enu_rad;
}

void VehicleFsm::enter(VehicleState s, VehicleOutputs& out, const std::string& why) {
  out.note = std::string(vehicle_state_name(state_)) + " -> " + vehicle_state_name(s) +
             (why.empty() ? "" : ": ") + why;
  state_ = s;
  state_since_s_ = now_s_;
}

void VehicleFsm::start_landing(VehicleOutputs& out, const std::string& why) {
  if (airspace_held_ || request_) {
    out.airspace = std::optional<AirspaceArea>();  // NaN: release
    airspace_held_ = false;
    request_.reset();
  }
  land_phase_ = LandPhase::kClimbToTransit;
  enter(VehicleState::kLand, out, why);
}

// the nearest confirmed balloon in this UAV's half, inside the arena, not where we already popped
// one
std::optional<BalloonSighting> VehicleFsm::choose_target(const VehicleInputs& in) const {
  std::optional<BalloonSighting> best;
  double best_range = config_.max_target_range_m;
  for (const BalloonSighting& b : in.balloons) {
    if (in.now_s - b.last_seen_s > kFreshSighting_s) continue;
    const Eigen::Vector3d& p = b.position_enu_m;
    if (p.x() < config_.arena_x_min_m + kArenaMargin_m ||
        p.x() > config_.arena_x_max_m - kArenaMargin_m ||
        p.y() < config_.arena_y_min_m + kArenaMargin_m ||
        p.y() > config_.arena_y_max_m - kArenaMargin_m) {
      continue;
    }
    if (!in_own_half(p)) continue;
    bool done = false;
    for (const Eigen::Vector2d& q : popped_at_)
      done = done || (q - p.head<2>()).norm() < kPoppedExclusion_m;
    if (done) continue;
    const double range = (p.head<2>() - in.position_enu_m.head<2>()).norm();
    if (range < best_range) {
      best_range = range;
      best = b;
    }
  }
  return best;
}

// "Whenever a green balloon is detected, a transition to the Area Allocation Request is immediately
// executed": the request is the segment from here to just past the balloon
void VehicleFsm::request_airspace(const VehicleInputs& in, const BalloonSighting& b,
                                  VehicleOutputs& out) {
  const Eigen::Vector3d& p = in.position_enu_m;
  target_ = b;
  pierce_start_enu_m_ = {p.x(), line_y_m(), hold_altitude_m_};
  const Eigen::Vector2d dir = (b.position_enu_m.head<2>() - p.head<2>()).normalized();
  request_ =
      AirspaceArea{p.head<2>(), b.position_enu_m.head<2>() + config_.pierce_overshoot_m * dir};
  out.airspace = request_;
  hover(in, out, inward_yaw_rad());
  enter(VehicleState::kAreaAllocationRequest, out,
        fmt("balloon at (%.1f, %.1f, %.1f)", b.position_enu_m.x(), b.position_enu_m.y(),
            b.position_enu_m.z()));
}

VehicleOutputs VehicleFsm::step(const VehicleInputs& raw) {
  VehicleOutputs out = decide(raw);
  limit_yaw_rate(raw, out);
  return out;
}

void VehicleFsm::limit_yaw_rate(const VehicleInputs& in, VehicleOutputs& out) {
  if (out.action != VehicleOutputs::Action::kVelocity) {
    yaw_cmd_s_ = -1.0;  // the next setpoint starts from where the vehicle points
    return;
  }
  if (yaw_cmd_s_ < 0.0) {
    yaw_cmd_rad_ = in.yaw_enu_rad;
    yaw_cmd_s_ = in.now_s;
  }
  const double max_step_rad = kMaxYawRate_rad_s * std::max(in.now_s - yaw_cmd_s_, 0.0);
  yaw_cmd_rad_ = wrap_pi(yaw_cmd_rad_ + std::clamp(wrap_pi(out.yaw_enu_rad - yaw_cmd_rad_),
                                                   -max_step_rad, max_step_rad));
  yaw_cmd_s_ = in.now_s;
  out.yaw_enu_rad = yaw_cmd_rad_;
}

VehicleOutputs VehicleFsm::decide(const VehicleInputs& raw) {
  VehicleOutputs out;
  out.camera_pitch_rad = config_.camera_pitch_rad;
  const VehicleInputs in = above_take_off_spot(raw);
  now_s_ = in.now_s;
  if (in.armed) armed_seen_ = true;

  // GCS commands (STATE topic) and a motor failure apply in any state
  if (apply_gcs_commands(raw, out) || motors_lost(in, out)) return out;

  switch (state_) {
    case VehicleState::kPreflight:
    case VehicleState::kLanded:
    case VehicleState::kFailed:
      break;
    case VehicleState::kTakeOff:
      on_take_off(in, out);
      break;
    case VehicleState::kGoSideCenter:
      on_go_side_center(in, out);
      break;
    case VehicleState::kGoScanAltitude:
      on_go_scan_altitude(in, out);
      break;
    case VehicleState::kBlindScan:
      on_blind_scan(in, out);
      break;
    case VehicleState::kScansDone:
      on_scans_done(in, out);
      break;
    case VehicleState::kAreaAllocationRequest:
      on_area_allocation_request(in, out);
      break;
    case VehicleState::kPierce:
      on_pierce(in, out);
      break;
    case VehicleState::kBackOff:
      on_back_off(in, out);
      break;
    case VehicleState::kLand:
      on_land(in, out);
      break;
  }
  return out;
}

VehicleInputs VehicleFsm::above_take_off_spot(const VehicleInputs& raw) {
  // heights above the take-off spot: the barometer's altitude on the ground before take-off is the
  // estimator's offset there (its drift, up to a metre in the field, changes over minutes, not
  // seconds); every height below, the balloons' included, is taken from it
  if (state_ == VehicleState::kPreflight && !raw.armed && raw.on_ground) {
    ground_z_m_ = raw.position_enu_m.z() - config_.rest_height_m;
  }
  VehicleInputs in = raw;
  in.position_enu_m.z() -= ground_z_m_;
  for (BalloonSighting& b : in.balloons) b.position_enu_m.z() -= ground_z_m_;
  return in;
}

bool VehicleFsm::apply_gcs_commands(const VehicleInputs& raw, VehicleOutputs& out) {
  for (GcsCommand c : raw.commands) {
    if (c == GcsCommand::kTakeOver && !take_over_) {
      take_over_ = true;
      out.note = "take over: the other UAV is out, every balloon is ours";
    } else if (c == GcsCommand::kReTask && !retask_) {
      retask_ = true;
      out.note = "re-task: the other half's balloons are ours too";
    } else if (c == GcsCommand::kLand && state_ != VehicleState::kLand &&
               state_ != VehicleState::kLanded && state_ != VehicleState::kFailed) {
      if (state_ == VehicleState::kPreflight) {
        enter(VehicleState::kLanded, out, "GCS land before start");
      } else {
        start_landing(out, "GCS land command");
      }
      return true;
    } else if (c == GcsCommand::kStart && state_ == VehicleState::kPreflight) {
      enter(VehicleState::kTakeOff, out,
            fmt("GCS start (ground at z=%.2f m)", raw.position_enu_m.z()));
      out.action = VehicleOutputs::Action::kArmAndTakeOff;
      out.takeoff_altitude_m = config_.takeoff_altitude_m;
      return true;
    }
  }
  return false;
}

// motors gone while flying (seed 7.2 Competition Day 2: "a malfunction in one UAV")
bool VehicleFsm::motors_lost(const VehicleInputs& in, VehicleOutputs& out) {
  const bool flying = state_ != VehicleState::kPreflight && state_ != VehicleState::kLanded &&
                      state_ != VehicleState::kFailed && state_ != VehicleState::kLand;
  if (!flying || !armed_seen_ || in.armed || state_since_s_ + 1.0 >= now_s_) return false;
  if (airspace_held_ || request_) out.airspace = std::optional<AirspaceArea>();
  airspace_held_ = false;
  request_.reset();
  enter(VehicleState::kFailed, out, "disarmed in the air");
  return true;
}

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
  const double along_m = steer_pierce(in, out);
  // "this state is maintained for N seconds after the balloon was last detected" (or until the
  // blades are through it)
  const bool seen = in.now_s - target_.last_seen_s < kFreshSighting_s;
  const bool through = !seen && along_m >= config_.pierce_overshoot_m;
  const bool coasted = in.now_s - target_.last_seen_s > config_.pierce_coast_s;
  const bool timeout = in.now_s - state_since_s_ > config_.pierce_timeout_s;
  const bool turned = coast_dir_.dot(pierce_dir_) < std::cos(kPierceMaxTurn_rad);
  if (!through && !coasted && !timeout && !turned) return;
  // the camera cannot tell a pop (it lost the balloon at close range): if the blades got
  // there, look back at it while backing off; POPPED is reported only if it is not seen again
  pierce_reached_ = closest_blade_m_ < 0.35 || along_m > -0.2;
  pierce_through_ = through;
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
  const double blade_z = std::clamp(b.z() + config_.pierce_blade_above_centre_m,
                                    p.z() - kMaxPierceClimb_m, p.z() + kMaxPierceClimb_m);
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
  if (back && pierce_reached_ && !pierce_through_ && !seen_again_) {
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
    popped_at_.push_back(b);
    out.popped_enu_m = b;
    why += ", balloon gone (" + std::to_string(popped_) + " popped)";
  } else {
    why += seen_again_ ? ", the balloon is still there" : "";
  }
  enter(VehicleState::kBlindScan, out, why);
}

// "reaches a pre-designated landing spot, starts a slow descent and, eventually, turns off the
// motors"
void VehicleFsm::on_land(const VehicleInputs& in, VehicleOutputs& out) {
  switch (land_phase_) {
    case LandPhase::kClimbToTransit:
      land_climb_to_transit(in, out);
      break;
    case LandPhase::kToSpot:
      land_to_spot(in, out);
      break;
    case LandPhase::kAlignSkids:
      land_align_skids(in, out);
      break;
    case LandPhase::kDescend:
      land_descend(in, out);
      break;
    case LandPhase::kMotorsOff:
      if (!in.armed) enter(VehicleState::kLanded, out, "motors off");
      break;
  }
}

double VehicleFsm::landing_transit_altitude_m() const {
  return index_ == 0 ? config_.landing_transit_altitude_s0_m
                     : config_.landing_transit_altitude_s1_m;
}

void VehicleFsm::land_climb_to_transit(const VehicleInputs& in, VehicleOutputs& out) {
  const Eigen::Vector3d& p = in.position_enu_m;
  const double transit_z = landing_transit_altitude_m();
  out.action = VehicleOutputs::Action::kVelocity;
  out.velocity_enu_m_s = toward(p, {p.x(), p.y(), transit_z}, 0.0);
  out.yaw_enu_rad = in.yaw_enu_rad;
  if (std::abs(p.z() - transit_z) < 0.3) land_phase_ = LandPhase::kToSpot;
}

void VehicleFsm::land_to_spot(const VehicleInputs& in, VehicleOutputs& out) {
  const Eigen::Vector3d& p = in.position_enu_m;
  const Eigen::Vector3d spot(landing_spot_enu_m_.x(), landing_spot_enu_m_.y(),
                             landing_transit_altitude_m());
  const double d = (spot.head<2>() - p.head<2>()).norm();
  out.action = VehicleOutputs::Action::kVelocity;
  out.velocity_enu_m_s =
      toward(p, spot,
             std::min(config_.transit_speed_m_s, std::sqrt(2.0 * kLandingApproachDecel_m_s2 * d)));
  out.yaw_enu_rad = in.yaw_enu_rad;
  if (d < 0.5 && in.velocity_enu_m_s.head<2>().norm() < kLandingStillSpeed_m_s) {
    land_phase_ = LandPhase::kAlignSkids;
    descent_stopped_s_ = -1.0;
    steady_descent_s_ = -1.0;
    steady_descent_ = false;
    touchdown_gate_.reset();
    descent_paused_ = false;
    descent_since_s_ = in.now_s;
    stop_rule_from_s_ = in.now_s;
    out.note = "over the landing spot: laying the skids along the wind";
  }
}

void VehicleFsm::land_align_skids(const VehicleInputs& in, VehicleOutputs& out) {
  // at the transit altitude over the spot: the hover's lean tells the wind (touchdown_gate),
  // and the heading turns the skids along it here, high up. A turn near the ground
  // saturated the mixer's collective (it keeps yaw torque first) and the UAV sank at
  // 2.5 m/s onto the ground, commanded to climb (two-UAV field seed 1, uav0, with the turn
  // made during the descent).
  touchdown_gate_.update(in.now_s, in.velocity_enu_m_s.head<2>(), in.roll_rad, in.pitch_rad,
                         in.yaw_enu_rad);
  const std::optional<double> skid_yaw = touchdown_gate_.skid_yaw_enu_rad(in.yaw_enu_rad);
  const double spent_s = in.now_s - descent_since_s_;
  out.action = VehicleOutputs::Action::kVelocity;
  out.velocity_enu_m_s =
      toward(in.position_enu_m,
             {landing_spot_enu_m_.x(), landing_spot_enu_m_.y(), landing_transit_altitude_m()}, 0.5);
  out.yaw_enu_rad =
      spent_s < kLandingWindRead_s ? in.yaw_enu_rad : skid_yaw.value_or(in.yaw_enu_rad);
  const bool aligned =
      !skid_yaw || std::abs(wrap_pi(*skid_yaw - in.yaw_enu_rad)) < kLandingSkidAlign_rad;
  if ((spent_s >= kLandingWindRead_s && aligned) || spent_s >= kLandingAlignMax_s) {
    land_phase_ = LandPhase::kDescend;
    landing_yaw_rad_ = in.yaw_enu_rad;
    stop_rule_from_s_ = in.now_s;
    out.note =
        skid_yaw ? fmt("skids along the wind (from %.0f deg): descending",
                       std::atan2(touchdown_gate_.lean_enu().y(), touchdown_gate_.lean_enu().x()) *
                           180.0 / kPi)
                 : std::string("no wind to read: descending");
  }
}

void VehicleFsm::land_descend(const VehicleInputs& in, VehicleOutputs& out) {
  // our own descent, on velocity alone near the ground, and the motors off at touchdown. The
  // autopilot's LAND holds the position where it began; in the field (GPS bias wandering, a
  // gust) that hold leans the vehicle against the ground once a leg touches: field seed 1
  // (uav1) sat 1.5 s on one leg at 27 deg roll, then tipped a propeller into the ground
  // before LAND's land detector (1 s of low thrust) disarmed it.
  const Eigen::Vector3d& p = in.position_enu_m;
  const double h = p.z();  // above the take-off spot
  Eigen::Vector3d v(0.0, 0.0, h > 2.0 ? -1.0 : -0.5);
  if (h > 1.0) {
    v.head<2>() = toward(p, {landing_spot_enu_m_.x(), landing_spot_enu_m_.y(), h}, 0.5).head<2>();
  }
  // The last 2 m (the 0.5 m/s band) go on only while the gate says calm: no sideways speed
  // (touchdown_gate.hpp; two-UAV field seeds 1 and 12 tipped over their gear at touchdown
  // in gusts). The heading stays where the skids were laid along the wind.
  const bool calm = touchdown_gate_.update(in.now_s, in.velocity_enu_m_s.head<2>(), in.roll_rad,
                                           in.pitch_rad, in.yaw_enu_rad);
  const bool pause = h <= 2.0 && !calm;
  if (pause != descent_paused_) {
    descent_paused_ = pause;
    out.note = pause ? fmt("descent paused (climbing) at %.2f m: %.2f m/s sideways", h,
                           in.velocity_enu_m_s.head<2>().norm())
                     : fmt("descent resumed at %.2f m", h);
  }
  if (pause) {
    // not a hover but a slow climb: the height is the barometer's, which may have drifted
    // by a metre and more since take-off (one-UAV field seed 17: on the ground at 1.96 m),
    // and a hover commanded on the ground holds the vehicle there at hover thrust, light on
    // its skids, where it slid about in the gust and tipped a propeller into the ground 11 s
    // later; a climb lifts it off instead. A commanded climb is neither the end of a steady
    // descent nor the ground; the stop rule counts again a second after the descent resumes
    // (the vehicle needs a few tenths of a second to reach 0.2 m/s down again)
    v.z() = kLandingPauseClimb_m_s;
    steady_descent_s_ = -1.0;
    steady_descent_ = false;
    descent_stopped_s_ = -1.0;
    stop_rule_from_s_ = in.now_s + 1.0;
  }
  out.action = VehicleOutputs::Action::kVelocity;
  out.velocity_enu_m_s = v;
  out.yaw_enu_rad = landing_yaw_rad_;
  if (touched_down(in, h, pause)) {
    land_phase_ = LandPhase::kMotorsOff;
    out.action = VehicleOutputs::Action::kDisarm;
    out.note = fmt("touchdown at %.2f m: motors off", h);
  }
}

bool VehicleFsm::touched_down(const VehicleInputs& in, double h, bool pause) {
  // touchdown: the 0.5 m/s descent stops within a telemetry sample or two when the gear
  // meets the ground (in the air the velocity loop holds it to a few cm/s; turbulence's
  // vertical drag is ~0.4 % of the weight), and the vehicle must be off before it pivots on
  // the upwind leg: field seed 15 (uav0) rolled from 8 to 43 deg in 0.6 s on the ground, prop
  // into the ground. The height only bounds it loosely: the baro had drifted +1.0 m since
  // take-off there (estimated 1.12 m at rest on the ground).
  // Only a stop that ends a steady 0.5 m/s descent (a second of it) counts: one-UAV field
  // seed 9 sank at 2.1 m/s (the controller's vertical loop gives way while braking), and its
  // recovery passed -0.16 m/s at 2 m: disarmed there, it fell at 5.3 m/s.
  // The second must be unbroken: a recovery that passes through the band and overshoots
  // upwards does not count.
  const double vz = in.velocity_enu_m_s.z();
  if (pause) {
    // (reset by the pause)
  } else if (vz <= -0.8) {
    steady_descent_s_ = -1.0;
    steady_descent_ = false;
  } else if (vz < -0.3) {
    if (steady_descent_s_ < 0.0) steady_descent_s_ = in.now_s;
    steady_descent_ = steady_descent_ || in.now_s - steady_descent_s_ >= 1.0;
  } else if (!steady_descent_) {
    steady_descent_s_ = -1.0;
  }
  // Without that second (a sink ended on the ground: one-UAV field seed 9 bounced there,
  // its motors on), a stop held for a second is the ground too: in the air the commanded
  // 0.5 m/s descent does not stay stopped that long.
  const bool stopped = !pause && in.now_s >= stop_rule_from_s_ && h < 2.5 && vz > -0.2 && vz < 0.2;
  if (!stopped) descent_stopped_s_ = -1.0;
  if (stopped && descent_stopped_s_ < 0.0) descent_stopped_s_ = in.now_s;
  const double stopped_s = descent_stopped_s_ < 0.0 ? -1.0 : in.now_s - descent_stopped_s_;
  return in.on_ground || (steady_descent_ && stopped_s >= 0.05) || stopped_s >= 1.0;
}

}  // namespace uavsim::missions::mbzirc2020
