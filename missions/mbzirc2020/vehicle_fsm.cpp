#include "vehicle_fsm.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "uavsim/client/geodesy.hpp"
#include "uavsim/common/angles.hpp"
#include "vehicle_fsm_tuning.hpp"

namespace uavsim::missions::mbzirc2020 {
namespace {

using client::wrap_pi;
using namespace vehicle_tuning;  // the machine's own constants, unqualified

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
    for (const Eigen::Vector3d& q : popped_at_)
      done = done || (q.head<2>() - p.head<2>()).norm() < kPoppedExclusion_m;
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

}  // namespace uavsim::missions::mbzirc2020
