#include "landing_fsm.hpp"

#include <algorithm>
#include <cmath>

#include "uavsim/common/fmt.hpp"

namespace uavsim::missions::mbzirc2017 {

namespace {
using common::fmt;

constexpr double kTakeoffRetry_s = 5.0;
constexpr double kReachedAltitudeMargin_m = 1.0;
constexpr double kOpenLoopReadyBand_m = 0.5;  // readiness from sightings this far above it

client::PidGains approach_gains(const MissionConfig& c) {
  client::PidGains g;
  g.kp = c.approach_kp_1_s;
  g.ki = c.approach_ki_1_s2;
  g.kd = c.approach_kd;
  g.output_min = -c.approach_max_speed_m_s;
  g.output_max = c.approach_max_speed_m_s;
  g.integral_limit = 1.0;  // m/s: the integral only trims the feed-forward
  g.derivative_filter_s = 0.2;
  return g;
}

Eigen::Vector2d clamp_norm(const Eigen::Vector2d& v, double max) {
  const double n = v.norm();
  return n > max ? Eigen::Vector2d(v * (max / n)) : v;
}
}  // namespace

const char* landing_state_name(LandingState s) {
  switch (s) {
    case LandingState::kStart:
      return "Start";
    case LandingState::kGoToCentre:
      return "GoToCentre";
    case LandingState::kIntercept:
      return "Intercept";
    case LandingState::kWaitUntilVisible:
      return "WaitUntilVisible";
    case LandingState::kApproach:
      return "Approach";
    case LandingState::kLanded:
      return "Landed";
  }
  return "?";
}

LandingFsm::LandingFsm(const MissionConfig& config)
    : config_(config),
      funnel_(config),
      envelope_(config),
      pid_x_(approach_gains(config)),
      pid_y_(approach_gains(config)) {}

double LandingFsm::height_above_deck_m(double z_enu_m) const {
  return z_enu_m - config_.skid_depth_m - config_.deck_height_m;
}

void LandingFsm::enter(LandingState s, double now_s, FsmOutputs* out, const std::string& why) {
  // several transitions in one step each leave their line
  out->note += std::string(out->note.empty() ? "" : "\n") + "state " + landing_state_name(state_) +
               " -> " + landing_state_name(s) + (why.empty() ? "" : ": " + why);
  state_ = s;
  entered_s_ = now_s;
  if (s == LandingState::kApproach) {
    pid_x_.reset();
    pid_y_.reset();
    lost_since_s_.reset();
    open_loop_since_s_.reset();
    outside_reported_ = false;
    open_loop_reported_ = false;
    ready_for_open_loop_ = false;
    climb_away_ = false;
    give_up_after_climb_ = false;
    settling_reported_ = false;
    rebuilding_since_s_.reset();
  }
}

double LandingFsm::hold_altitude_m_s(const FsmInputs& in, double altitude_m) const {
  return std::clamp(config_.altitude_gain_1_s * (altitude_m - in.position_enu_m.z()),
                    -config_.max_climb_m_s, config_.max_climb_m_s);
}

Eigen::Vector3d LandingFsm::fly_to(const FsmInputs& in, const Eigen::Vector2d& target_enu_m,
                                   double speed_m_s, double altitude_m) const {
  // P on the distance, saturated at the cruise speed (the FC's input shaping limits the
  // acceleration)
  const Eigen::Vector2d v = clamp_norm(target_enu_m - in.position_enu_m.head<2>(), speed_m_s);
  return Eigen::Vector3d(v.x(), v.y(), hold_altitude_m_s(in, altitude_m));
}

bool LandingFsm::seen_since(const FsmInputs& in, double since_s) const {
  return in.truck.last_seen_s >= since_s &&
         in.now_s - in.truck.last_seen_s <= config_.seen_recently_s;
}

FsmOutputs LandingFsm::step(const FsmInputs& in) {
  FsmOutputs out;
  step_dt_s_ = last_step_s_ < 0 ? 0.0 : in.now_s - last_step_s_;
  last_step_s_ = in.now_s;
  if (state_ == LandingState::kStart) {
    on_start(in, out);
    return out;
  }
  // one handler per state; each returns true when it has commanded the step. One that hands over
  // returns false, and the next state in the seed's order acts in the same step (Go To Centre ->
  // Intercept -> Wait Until Visible)
  if (state_ == LandingState::kGoToCentre && on_go_to_centre(in, out)) return out;
  if (state_ == LandingState::kIntercept && on_intercept(in, out)) return out;
  if (state_ == LandingState::kWaitUntilVisible && on_wait_until_visible(in, out)) return out;
  if (state_ == LandingState::kApproach && out.note.empty()) return approach(in);
  if (state_ == LandingState::kLanded) {
    // keep the motors off: repeat the force disarm while telemetry still says armed
    if (in.armed) out.action = FsmOutputs::Action::kForceDisarm;
    return out;
  }
  // a transition happened above: the new state acts from the next step; hold meanwhile
  if (out.action == FsmOutputs::Action::kNone) {
    out.action = FsmOutputs::Action::kVelocity;
    const Eigen::Vector2d v = in.truck.initialised && state_ == LandingState::kApproach
                                  ? in.truck.velocity_enu_m_s
                                  : Eigen::Vector2d::Zero();
    out.velocity_enu_m_s = Eigen::Vector3d(v.x(), v.y(), 0.0);
  }
  return out;
}

void LandingFsm::on_start(const FsmInputs& in, FsmOutputs& out) {
  // take off (retried while the vehicle is not armed), then Go To Centre near the altitude
  if (!in.armed && (!takeoff_sent_ || in.now_s - takeoff_sent_s_ > kTakeoffRetry_s)) {
    takeoff_sent_ = true;
    takeoff_sent_s_ = in.now_s;
    out.action = FsmOutputs::Action::kArmAndTakeOff;
    out.takeoff_altitude_m = config_.cruise_altitude_m;
    out.note = fmt("take-off to %.1f m", config_.cruise_altitude_m);
    return;
  }
  if (in.armed && in.position_enu_m.z() > config_.cruise_altitude_m - kReachedAltitudeMargin_m) {
    enter(LandingState::kGoToCentre, in.now_s, &out, "");
  }
}

bool LandingFsm::on_go_to_centre(const FsmInputs& in, FsmOutputs& out) {
  if (in.truck.initialised && seen_since(in, entered_s_)) {
    enter(LandingState::kIntercept, in.now_s, &out,
          fmt("truck seen at (%.1f, %.1f), filter initialised", in.truck.position_enu_m.x(),
              in.truck.position_enu_m.y()));
    return false;
  }
  out.action = FsmOutputs::Action::kVelocity;
  out.velocity_enu_m_s =
      fly_to(in, config_.arena_centre_enu_m, config_.cruise_speed_m_s, config_.cruise_altitude_m);
  return true;
}

bool LandingFsm::on_intercept(const FsmInputs& in, FsmOutputs& out) {
  if (!in.truck.initialised || !in.truck.interception_enu_m) {
    enter(LandingState::kGoToCentre, in.now_s, &out, "no track of the truck");
    out.action = FsmOutputs::Action::kVelocity;
    out.velocity_enu_m_s =
        fly_to(in, config_.arena_centre_enu_m, config_.cruise_speed_m_s, config_.cruise_altitude_m);
    return true;
  }
  const Eigen::Vector2d point = *in.truck.interception_enu_m;
  const double distance = (point - in.position_enu_m.head<2>()).norm();
  // in view already (caught up from behind, where the meeting point keeps moving ahead): wait
  if (seen_since(in, entered_s_)) {
    enter(LandingState::kWaitUntilVisible, in.now_s, &out, "truck in view on the way");
    return false;
  }
  // there, or about to meet the truck (from behind, the meeting point moves on as the UAV
  // slows)
  if (distance < config_.arrive_radius_m ||
      in.truck.interception_time_to_go_s < config_.arrive_time_s) {
    enter(LandingState::kWaitUntilVisible, in.now_s, &out,
          fmt("on the interception point (%.1f, %.1f)", point.x(), point.y()));
    return false;
  }
  out.action = FsmOutputs::Action::kVelocity;
  out.velocity_enu_m_s = fly_to(in, point, config_.cruise_speed_m_s, config_.cruise_altitude_m);
  return true;
}

bool LandingFsm::on_wait_until_visible(const FsmInputs& in, FsmOutputs& out) {
  if (seen_since(in, entered_s_)) {
    misses_ = 0;
    enter(LandingState::kApproach, in.now_s, &out, "marker in view");
    return false;
  }
  if (in.now_s - entered_s_ > config_.search_timeout_s) {
    ++misses_;
    if (misses_ == 1) {
      enter(LandingState::kIntercept, in.now_s, &out, "not seen in 12 s (first miss)");
    } else {
      misses_ = 0;
      enter(LandingState::kGoToCentre, in.now_s, &out, "not seen in 12 s (second miss)");
    }
    out.action = FsmOutputs::Action::kVelocity;
    out.velocity_enu_m_s = Eigen::Vector3d(0, 0, hold_altitude_m_s(in, config_.cruise_altitude_m));
    return true;
  }
  // move at half the truck's speed along its way: the smallest speed difference when it comes
  const Eigen::Vector2d v = in.truck.initialised ? Eigen::Vector2d(0.5 * in.truck.velocity_enu_m_s)
                                                 : Eigen::Vector2d::Zero();
  out.action = FsmOutputs::Action::kVelocity;
  out.velocity_enu_m_s =
      Eigen::Vector3d(v.x(), v.y(), hold_altitude_m_s(in, config_.cruise_altitude_m));
  return true;
}

FsmOutputs LandingFsm::climb_away(const FsmInputs& in, const EstimatedTruck& truck,
                                  const TruckRelative& rel, const std::string& why, bool give_up) {
  FsmOutputs out;
  climb_away_ = true;
  give_up_after_climb_ = give_up;
  ++climb_aways_;
  out.note = "climb-away: " + why;
  out.action = FsmOutputs::Action::kVelocity;
  out.velocity_enu_m_s =
      enu_velocity_for(truck, in.position_enu_m, envelope_.abort_velocity_m_s(rel.position_m));
  return out;
}

double LandingFsm::blind_height_m(const FsmInputs& in) const {
  return config_.marker_lost_height_m - (open_loop_start_z_m_ - in.position_enu_m.z());
}

FsmOutputs LandingFsm::approach_while_settling(const FsmInputs& in, double h) {
  // Neither the UAV's position relative to the truck (its own position stepped; the track was made
  // before) nor its velocity (the FC flies its own estimate, off meanwhile) can be trusted, so the
  // envelope's checks and the PID, which work on them, would act on the error: a climb-away's
  // retreat and the PID's correction add to the drift the FC makes anyway. The truck's velocity
  // does not depend on it, nor do height changes (barometric). So: follow the truck's velocity
  // alone, and decide by height. In the blind last metres, low, the deck is nearer than any way out
  // (issue 36's seed 52: the FC's drift put a propeller in the cab 0.9 s after the step, the
  // climb-away still sinking): motors off onto the deck. Blind and higher, or below the floor:
  // climb, the drift then carries the UAV over the cab's top, not into it. Above the floor: hold;
  // nothing reaches the cab from there.
  FsmOutputs out;
  const bool blind_descent = open_loop_since_s_.has_value();
  if (blind_descent) {
    const double h_blind = blind_height_m(in);
    if (h_blind <= config_.drop_height_m) {
      enter(LandingState::kLanded, in.now_s, &out,
            fmt("position estimate stepped (a GPS jump?) %.2f m above the deck in the blind last "
                "metres: motors off onto the deck",
                h_blind));
      out.action = FsmOutputs::Action::kForceDisarm;
      return out;
    }
  }
  const bool climb = blind_descent || h < envelope_.floor_height_m();
  if (!settling_reported_) {
    settling_reported_ = true;
    out.note = fmt("position estimate stepped (a GPS jump?) at %.2f m: following the truck's "
                   "velocity, ",
                   h) +
               (climb ? "climbing" : "holding");
  }
  pid_x_.reset();
  pid_y_.reset();
  const Eigen::Vector2d v_xy =
      in.truck.initialised ? clamp_norm(in.truck.velocity_enu_m_s, config_.approach_max_speed_m_s)
                           : Eigen::Vector2d::Zero();
  out.action = FsmOutputs::Action::kVelocity;
  out.velocity_enu_m_s = Eigen::Vector3d(v_xy.x(), v_xy.y(), climb ? config_.abort_climb_m_s : 0.0);
  return out;
}

FsmOutputs LandingFsm::approach_while_rebuilding(const FsmInputs& in, double h) {
  // The estimate has settled after a step, but the truck's track is from before it: its marker is
  // up to the step's size off against the UAV's position now (issue 36's seed 172: ~2 m, a blind
  // descent "centred" 1.7 m ahead of the marker, onto the cab's corner). Until the track has been
  // made again from sightings taken since, nothing is decided from the relative position: follow
  // the truck's velocity (the step does not touch it) and climb as when the marker is lost, which
  // takes the UAV over the cab's top and widens the camera's view of the deck; the funnel takes
  // over again from the new track's first sightings. No new track within the give-up time: Go To
  // Centre, as for a lost marker.
  FsmOutputs out;
  pid_x_.reset();
  pid_y_.reset();
  lost_since_s_.reset();
  open_loop_since_s_.reset();
  open_loop_reported_ = false;
  ready_for_open_loop_ = false;
  climb_away_ = false;
  if (!rebuilding_since_s_) {
    rebuilding_since_s_ = in.now_s;
    out.note =
        fmt("estimate settled at %.2f m: the truck's track is made again from new "
            "sightings; climbing, following its velocity",
            h);
  }
  if (in.now_s - *rebuilding_since_s_ > config_.lost_give_up_s) {
    enter(LandingState::kGoToCentre, in.now_s, &out,
          "no new track of the truck 8 s after the step");
    out.action = FsmOutputs::Action::kVelocity;
    out.velocity_enu_m_s = Eigen::Vector3d(0, 0, hold_altitude_m_s(in, config_.cruise_altitude_m));
    return out;
  }
  const Eigen::Vector2d v_xy =
      clamp_norm(in.truck.velocity_enu_m_s, config_.approach_max_speed_m_s);
  // below the floor at the climb-away's rate: the truck's position is not known well enough to
  // stay there
  const double vz = h < envelope_.floor_height_m()                      ? config_.abort_climb_m_s
                    : in.position_enu_m.z() < config_.cruise_altitude_m ? config_.climb_m_s
                                                                        : 0.0;
  out.action = FsmOutputs::Action::kVelocity;
  out.velocity_enu_m_s = Eigen::Vector3d(v_xy.x(), v_xy.y(), vz);
  return out;
}

FsmOutputs LandingFsm::approach(const FsmInputs& in) {
  FsmOutputs out;
  // a pad switch closed: all motors off at once (seed 7.1 "Landed")
  if (in.switch_closed) {
    enter(LandingState::kLanded, in.now_s, &out, "pad switch closed: motors off");
    out.action = FsmOutputs::Action::kForceDisarm;
    return out;
  }
  const double h = height_above_deck_m(in.position_enu_m.z());
  if (in.estimate_settling) return approach_while_settling(in, h);
  settling_reported_ = false;
  if (in.truck.position_stale) return approach_while_rebuilding(in, h);
  rebuilding_since_s_.reset();

  // the UAV in the truck's frame, from its own estimate, and what the clearance envelope says
  ApproachView view;
  view.h = h;
  view.truck.marker_enu_m = in.truck.position_enu_m;
  view.truck.velocity_enu_m_s = in.truck.velocity_enu_m_s;
  view.truck.heading_enu_rad = in.truck.heading_enu_rad;
  view.truck.yaw_rate_rad_s = in.truck.yaw_rate_rad_s;
  view.rel = to_truck_frame(view.truck, config_, in.position_enu_m, in.velocity_enu_m_s);
  view.check = envelope_.check(view.rel);
  if (climb_away_ && !end_climb_away(in, view, out)) return out;

  // horizontal, then vertical; a vertical rule that ends the approach (a climb-away, Go To
  // Centre) leaves its command in out and no rate
  const bool fresh = in.now_s - in.truck.last_seen_s <= config_.fresh_sighting_s;
  const bool blind_low = !fresh && h <= config_.open_loop_height_m;
  const Eigen::Vector2d v_xy = approach_velocity_xy(in, blind_low);
  std::optional<double> vz;
  if (fresh) {
    vz = descent_in_sight_m_s(in, view, out);
  } else if (open_loop_since_s_ || (blind_low && !in.camera_dark)) {
    vz = descent_blind_m_s(in, view, out);
  } else if (!view.check.above_floor) {
    // lost below the cab's top and not because it is too close (the camera dark): no blind landing
    out = climb_away(in, view.truck, view.rel, fmt("marker lost at %.2f m with the camera dark", h),
                     false);
  } else if (in.now_s - in.truck.last_seen_s <= config_.lost_after_s && !in.camera_dark) {
    // a stale sighting up here: hold, no descent on it, until seen again or lost
    vz = 0.0;
  } else {
    vz = climb_when_lost_m_s(in, h, out);
  }
  if (!vz) return out;
  out.action = FsmOutputs::Action::kVelocity;
  out.velocity_enu_m_s = Eigen::Vector3d(v_xy.x(), v_xy.y(), *vz);
  return out;
}

bool LandingFsm::end_climb_away(const FsmInputs& in, const ApproachView& view, FsmOutputs& out) {
  // the climb-away: up and away from the cab along the truck's way until clear of the truck, then
  // a new approach (or Go To Centre after an open-loop descent that found no deck)
  if (view.h < config_.abort_clear_height_m) {
    out.action = FsmOutputs::Action::kVelocity;
    out.velocity_enu_m_s = enu_velocity_for(view.truck, in.position_enu_m,
                                            envelope_.abort_velocity_m_s(view.rel.position_m));
    return false;
  }
  climb_away_ = false;
  if (give_up_after_climb_) {
    enter(LandingState::kGoToCentre, in.now_s, &out, "clear of the truck after the climb-away");
    out.action = FsmOutputs::Action::kVelocity;
    out.velocity_enu_m_s = Eigen::Vector3d(0, 0, config_.climb_m_s);
    return false;
  }
  pid_x_.reset();
  pid_y_.reset();
  lost_since_s_.reset();
  open_loop_since_s_.reset();
  open_loop_reported_ = false;
  out.note = fmt("clear of the truck at %.1f m: approaching again", view.h);
  return true;
}

Eigen::Vector2d LandingFsm::approach_velocity_xy(const FsmInputs& in, bool blind_low) {
  // the truck's velocity (feed-forward from the filter) + PID on the offset to the marker (blind,
  // on a point behind it, away from the cab)
  const Eigen::Vector2d target =
      in.truck.position_enu_m -
      (blind_low ? config_.open_loop_aim_back_m : 0.0) *
          Eigen::Vector2d(std::cos(in.truck.heading_enu_rad), std::sin(in.truck.heading_enu_rad));
  Eigen::Vector2d correction(pid_x_.update(target.x(), in.position_enu_m.x(), step_dt_s_),
                             pid_y_.update(target.y(), in.position_enu_m.y(), step_dt_s_));
  // blind, a gentle correction only: no relative manoeuvre that the estimate cannot follow (seed
  // 148: 0.39 m ahead of the marker plus the aim back asked for 0.64 m/s backwards, and the UAV
  // went 0.9 m/s)
  if (blind_low) correction = clamp_norm(correction, config_.open_loop_correction_m_s);
  return clamp_norm(in.truck.velocity_enu_m_s + correction, config_.approach_max_speed_m_s);
}

// vertical: descend inside the funnel, climb outside it or when the marker is lost up high; in the
// last decimetres the marker no longer fits the image: open-loop descent, at most 8 s. The envelope
// bounds all of it: below the cab's top only in the deck box and matched, open loop only from
// centred and matched, otherwise the climb-away.
std::optional<double> LandingFsm::descent_in_sight_m_s(const FsmInputs& in,
                                                       const ApproachView& view, FsmOutputs& out) {
  const double h = view.h;
  const TruckRelative& rel = view.rel;
  lost_since_s_.reset();
  open_loop_since_s_.reset();
  if (!view.check.safe()) {
    out = climb_away(in, view.truck, rel,
                     fmt("%.2f m above the deck, (%+.2f, %+.2f) m from the centre", h,
                         rel.position_m.x(), rel.position_m.y()) +
                         fmt(" at %.2f m/s relative: outside the deck box or unmatched",
                             rel.velocity_m_s.head<2>().norm()),
                     false);
    return std::nullopt;
  }
  // the readiness for the blind last metres, from fresh sightings near where the marker leaves
  // the image
  ready_for_open_loop_ =
      view.check.ready_for_open_loop() && h <= config_.open_loop_height_m + kOpenLoopReadyBand_m;
  const double offset_m = (in.truck.position_enu_m - in.position_enu_m.head<2>()).norm();
  double vz = 0.0;
  if (funnel_.contains(h, offset_m)) {
    vz = -funnel_.descent_rate_m_s(h);
    outside_reported_ = false;
  } else {
    vz = config_.climb_m_s;
    if (!outside_reported_) {
      outside_reported_ = true;
      out.note = fmt("outside the funnel (%.2f m off at %.1f m): climbing", offset_m, h);
    }
  }
  // not below the commit height unless centred and matched, nor below the floor unless cleared
  if (!view.check.ready_for_open_loop()) {
    vz = std::max(vz, config_.floor_approach_gain_1_s * (config_.commit_height_m - h));
  }
  return envelope_.limit_vertical_m_s(rel, vz);
}

std::optional<double> LandingFsm::descent_blind_m_s(const FsmInputs& in, const ApproachView& view,
                                                    FsmOutputs& out) {
  // the marker left the image low down (too close to see, the camera still working): the blind
  // last metres, only from centred and matched
  const double h = view.h;
  const TruckRelative& rel = view.rel;
  if (!open_loop_since_s_) {
    if (!ready_for_open_loop_) {
      out = climb_away(
          in, view.truck, rel,
          fmt("marker lost at %.2f m, %.2f m from the centre at %.2f m/s relative: not centred "
              "and matched",
              h, rel.position_m.head<2>().norm(), rel.velocity_m_s.head<2>().norm()),
          false);
      return std::nullopt;
    }
    open_loop_since_s_ = in.now_s;
    open_loop_start_z_m_ = in.position_enu_m.z();
  }
  if (!open_loop_reported_) {
    open_loop_reported_ = true;
    out.note = fmt("marker too close to see at %.2f m: open-loop descent", h);
  }
  // blind, the height is where the marker left the image less the barometric descent since,
  // where the barometer's absolute altitude is lower (issue 36's seed 148: its drift said 0.36 m
  // more than the truth, so the floor's rule never held and the UAV, drifting back at 0.9 m/s,
  // sank off the deck's rear edge)
  const double h_blind = blind_height_m(in);
  TruckRelative rel_blind = rel;
  rel_blind.position_m.z() = std::min(h, h_blind);
  if (!envelope_.check(rel_blind).safe()) {
    out = climb_away(in, view.truck, rel_blind,
                     fmt("open loop at %.2f m left the deck box (%+.2f, %+.2f) or unmatched",
                         rel_blind.position_m.z(), rel.position_m.x(), rel.position_m.y()) +
                         fmt(" at %.2f m/s relative", rel.velocity_m_s.head<2>().norm()),
                     false);
    return std::nullopt;
  }
  // sunk below the deck's top without a touchdown: no deck under the skids, wherever the
  // estimate puts it
  if (h_blind < -config_.deck_missed_m) {
    out = climb_away(in, view.truck, rel_blind,
                     fmt("open loop %.2f m below the deck's top without a touchdown", -h_blind),
                     true);
    return std::nullopt;
  }
  if (in.now_s - *open_loop_since_s_ > config_.open_loop_timeout_s) {
    out =
        climb_away(in, view.truck, rel_blind, "no touchdown after 8 s of open-loop descent", true);
    return std::nullopt;
  }
  return envelope_.limit_vertical_m_s(rel_blind, -config_.open_loop_descent_m_s);
}

std::optional<double> LandingFsm::climb_when_lost_m_s(const FsmInputs& in, double h,
                                                      FsmOutputs& out) {
  if (!lost_since_s_) {
    lost_since_s_ = in.now_s;
    out.note = fmt("marker lost at %.1f m: climbing, following the filter", h);
  }
  if (in.now_s - *lost_since_s_ > config_.lost_give_up_s) {
    enter(LandingState::kGoToCentre, in.now_s, &out, "marker lost for 8 s");
    out.action = FsmOutputs::Action::kVelocity;
    out.velocity_enu_m_s = Eigen::Vector3d(0, 0, hold_altitude_m_s(in, config_.cruise_altitude_m));
    return std::nullopt;
  }
  return in.position_enu_m.z() < config_.cruise_altitude_m ? config_.climb_m_s : 0.0;
}

}  // namespace uavsim::missions::mbzirc2017
