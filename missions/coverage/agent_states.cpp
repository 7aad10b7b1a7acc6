// The coverage agent's states (fig. 4.6), one handler each, and run_state, which first applies the
// changes any state takes (a recall, the going-home broadcast, a new leader) and then runs the
// current state's handler.
#include <algorithm>
#include <cmath>

#include "agent.hpp"
#include "agent_tuning.hpp"

namespace uavsim::missions::coverage {

using namespace agent_tuning;  // the agent's own constants, unqualified

void Agent::run_state(const AgentInputs& in, AgentOutputs& out) {
  const bool lead = adb_.leader() == id_;
  change_role(lead, out);
  switch (state_) {
    case AgentState::kTakingOff:
      on_taking_off(in, lead, out);
      break;
    case AgentState::kQuerying:
      on_querying(in, out);
      break;
    case AgentState::kDeploying:
      on_deploying(in, out);
      break;
    case AgentState::kRunning:
      on_running(in, out);
      break;
    case AgentState::kWaiting:
      on_waiting(in, out);
      break;
    case AgentState::kNonLeader:
      on_non_leader(in, out);
      break;
    case AgentState::kGoingHome:
      on_going_home(in, lead, out);
      break;
    case AgentState::kLanded:
    case AgentState::kFailed:
      break;
  }
  if (out.action == AgentOutputs::Action::kVelocity)
    commanded_velocity_enu_m_s_ = out.velocity_enu_m_s.head<2>();
  else
    commanded_velocity_enu_m_s_.setZero();
}

void Agent::change_role(bool lead, AgentOutputs& out) {
  // a recall (a later round that surveys again): back to the flock, unless already landing
  if (recalled_) {
    recalled_ = false;
    complete_ = false;
    if (state_ == AgentState::kGoingHome && !land_sent_) {
      flock_.reset();
      enter(AgentState::kNonLeader, out, "recalled: pictures lost on the way home");
    }
  }
  // the "going home" broadcast ends the mission for everyone (fig. 4.6)
  if (going_home_heard_ && state_ != AgentState::kGoingHome && state_ != AgentState::kTakingOff) {
    enter(AgentState::kGoingHome, out, "going-home broadcast heard");
  }
  // role changes
  if (is_leader_state() && !lead) {
    flock_.reset();
    enter(AgentState::kNonLeader, out, "agent " + std::to_string(adb_.leader()) + " leads");
  } else if (state_ == AgentState::kNonLeader && lead) {
    enter(AgentState::kQuerying, out, "leader lost, lowest id left");
    start_query(out);
  }
}

void Agent::on_taking_off(const AgentInputs& in, bool lead, AgentOutputs& out) {
  if (!takeoff_sent_) {
    takeoff_sent_ = true;
    out.action = AgentOutputs::Action::kTakeOff;
    out.takeoff_altitude_m = config_.altitude_m;
    return;
  }
  const bool at_altitude =
      in.position_enu_m.z() >= config_.altitude_m - config_.altitude_tolerance_m;
  if (!at_altitude || in.now_s - state_since_s_ < kDiscovery_s) return;
  target_heading_rad_ = 0.0;
  if (going_home_heard_) {
    enter(AgentState::kGoingHome, out, "going-home broadcast heard");
  } else if (lead) {
    enter(AgentState::kQuerying, out, "lowest id");
    start_query(out);
  } else {
    enter(AgentState::kNonLeader, out, "agent " + std::to_string(adb_.leader()) + " leads");
  }
}

void Agent::on_querying(const AgentInputs& in, AgentOutputs& out) {
  fly_to(in, in.position_enu_m.head<2>(), 0.0, target_heading_rad_, out);
  if (aggregation_.complete(adb_.live_mask())) {
    finish_query(in, out);
  } else if (in.now_s - state_since_s_ > kQueryTimeout_s) {
    // name the agents that did not answer: the ADB holds them live, yet no result reached us
    const uint64_t missing = adb_.live_mask() & ~aggregation_.responded();
    out.note = "no answer from";
    for (int id = 0; id < 64; ++id) {
      if (!(missing >> id & 1u)) continue;
      out.note += ' ';
      out.note += std::to_string(id);
    }
    state_since_s_ = in.now_s;
    start_query(out);
  }
}

void Agent::on_deploying(const AgentInputs& in, AgentOutputs& out) {
  const Eigen::Vector2d here = in.position_enu_m.head<2>();
  const Eigen::Vector2d start = path_->points_enu_m.front();
  fly_to(in, start, config_.deploy_speed_m_s, target_heading_rad_, out);
  const bool aligned =
      std::abs(angle_diff(in.yaw_enu_rad, target_heading_rad_)) < config_.heading_tolerance_rad;
  if ((here - start).norm() < kAtStart_m && aligned && flock_in_line(in)) {
    enter(AgentState::kRunning, out, "flock in line");
  } else if (in.now_s - state_since_s_ > config_.deploy_timeout_s) {
    enter(AgentState::kRunning, out, "deploy timeout");
  }
}

void Agent::on_running(const AgentInputs& in, AgentOutputs& out) {
  if (rewind_hold_ || rewind_back_) {
    run_rewind(in, out);
    return;
  }
  const double dir = path_x_direction(*path_);
  const double end_x = path_->points_enu_m.back().x();
  if ((in.position_enu_m.x() - end_x) * dir >= 0.0) {
    enter(AgentState::kWaiting, out, "end of path");
    fly_to(in, in.position_enu_m.head<2>(), 0.0, target_heading_rad_, out);
    return;
  }
  const double y_ahead = path_y_at(*path_, in.position_enu_m.x() + dir * kLookahead_m);
  const double vy =
      saturate(kLateralGain_1_s * (y_ahead - in.position_enu_m.y()), config_.cruise_speed_m_s);
  out.action = AgentOutputs::Action::kVelocity;
  out.velocity_enu_m_s << dir * config_.cruise_speed_m_s, vy, altitude_rate(in, config_.altitude_m);
  out.yaw_rate_rad_s = yaw_rate_to(in, target_heading_rad_);
  out.yaw_enu_rad = target_heading_rad_;
}

void Agent::run_rewind(const AgentInputs& in, AgentOutputs& out) {
  if (rewind_hold_) {
    // an agent deep inside the line was lost: hold until its neighbours have closed the gap
    fly_to(in, in.position_enu_m.head<2>(), 0.0, target_heading_rad_, out);
    if (flock_in_line(in) || in.now_s - rewind_since_s_ > kRewindHold_s) {
      rewind_hold_ = false;
      rewind_back_ = true;
      out.note = "line closed after a loss: back " +
                 fmt("%.0f m", std::abs(in.position_enu_m.x() - rewind_x_m_));
    }
    return;
  }
  // back along the path (still facing the way it runs) to before the loss
  const Eigen::Vector2d back(rewind_x_m_, path_y_at(*path_, rewind_x_m_));
  fly_to(in, back, config_.cruise_speed_m_s, target_heading_rad_, out);
  if ((in.position_enu_m.x() - rewind_x_m_) * path_x_direction(*path_) <= 0.5) rewind_back_ = false;
}

void Agent::on_waiting(const AgentInputs& in, AgentOutputs& out) {
  fly_to(in, in.position_enu_m.head<2>(), 0.0, target_heading_rad_, out);
  if (flock_in_line(in) || in.now_s - state_since_s_ > kWaitTimeout_s) {
    enter(AgentState::kQuerying, out, "flock caught up");
    start_query(out);
  }
}

void Agent::on_non_leader(const AgentInputs& in, AgentOutputs& out) {
  const Eigen::Vector2d here = in.position_enu_m.head<2>();
  const auto it = adb_.records().find(adb_.leader());
  if (it == adb_.records().end()) {
    fly_to(in, here, 0.0, in.yaw_enu_rad, out);
    return;
  }
  const AgentRecord& leader = it->second;
  FlockInputs f;
  f.local_enu_m = here;
  f.local_heading_rad = in.yaw_enu_rad;
  f.leader_enu_m = {leader.x_m, leader.y_m};
  f.leader_heading_rad = leader.heading_rad;
  f.leader_velocity_enu_m_s = {leader.vx_m_s, leader.vy_m_s};
  for (const auto& [id, r] : adb_.records())
    if (!r.landed) f.others_enu_m.emplace_back(r.x_m, r.y_m);
  f.dt_s = std::max(1e-3, dt_s_);
  const FlockOutputs fo = flock_.step(f);
  target_heading_rad_ = leader.heading_rad;
  Eigen::Vector2d v = fo.velocity_enu_m_s;
  if (v.norm() > config_.max_speed_m_s) v *= config_.max_speed_m_s / v.norm();
  out.action = AgentOutputs::Action::kVelocity;
  out.velocity_enu_m_s << v, altitude_rate(in, config_.altitude_m);
  out.yaw_rate_rad_s = fo.yaw_rate_rad_s;
  out.yaw_enu_rad = leader.heading_rad;
}

void Agent::on_going_home(const AgentInputs& in, bool lead, AgentOutputs& out) {
  // climb or descend to our layer first, then fly home in it, then land
  if (land_sent_) {
    watch_landing(in, out);
    return;
  }
  if (verify_after_loss(in, out)) return;  // recalled: surveying again
  // The leader lands last, once every agent it hears has landed and any loss is checked: an
  // agent lost while the others descend is still noticed by one that can fly
  // (verify_after_loss). It waits low over its home, so its own landing after the last one is
  // short.
  const double layer_alt = config_.altitude_m + (id_ % config_.home_layers) * config_.home_layer_m;
  const bool hold = lead && (loss_pending_ || !adb_.all_landed());
  const double home_dist = (home_enu_m_ - in.position_enu_m.head<2>()).norm();
  if (home_dist < kHomeReached_m) home_reached_ = true;
  if (home_dist > kHomeLeft_m) home_reached_ = false;
  if (home_reached_ && hold) {
    fly_to(in, home_enu_m_, 0.0, in.yaw_enu_rad, out);
    out.velocity_enu_m_s.z() = altitude_rate(in, loss_pending_ ? layer_alt : kLeaderWaitAltitude_m);
    return;
  }
  if (home_reached_) {
    land_sent_ = true;
    out.action = AgentOutputs::Action::kLand;
    return;
  }
  out.action = AgentOutputs::Action::kVelocity;
  out.yaw_rate_rad_s = 0.0;
  // climb or descend to our layer on the spot, and set off only once the next layer's agents,
  // which left the survey altitude with us, are a layer above ours: an agent that sets off
  // while its neighbour still climbs through its layer crosses that neighbour's column (8 quads
  // in the point-mass FlockSim: 1.3 m apart)
  const double layer_index = id_ % config_.home_layers;
  const bool next_layer_clear =
      in.now_s - state_since_s_ >= (layer_index + 1.0) * config_.home_layer_m / kMaxClimb_m_s;
  if (std::abs(in.position_enu_m.z() - layer_alt) > config_.altitude_tolerance_m ||
      !next_layer_clear) {
    fly_to(in, in.position_enu_m.head<2>(), 0.0, in.yaw_enu_rad, out);
    out.velocity_enu_m_s.z() = altitude_rate(in, layer_alt);
    return;
  }
  out.velocity_enu_m_s << home_velocity(in, home_dist), altitude_rate(in, layer_alt);
}

void Agent::watch_landing(const AgentInputs& in, AgentOutputs& out) {
  if (!in.armed && descending_when_disarmed(in)) {
    // the vehicle died in its descent: its pictures died with it, and the flock must not
    // count them as held by a landed agent
    enter(AgentState::kFailed, out, "vehicle disarmed in its landing descent");
    return;
  }
  if (!in.armed && in.on_ground) {
    enter(AgentState::kLanded, out, "on the ground");
    adb_.set_local_landed(true);
  }
}

Eigen::Vector2d Agent::home_velocity(const AgentInputs& in, double home_dist) const {
  const Eigen::Vector2d here = in.position_enu_m.head<2>();
  Eigen::Vector2d v = (home_enu_m_ - here) / home_dist *
                      std::min({config_.home_speed_m_s, kHomeApproachGain_1_s * home_dist,
                                std::sqrt(2.0 * kHomeBraking_m_s2 * home_dist)});
  // steer away from agents in our layer (their ids tell their layers)
  for (const auto& [id, r] : adb_.records()) {
    if (r.landed || id % config_.home_layers != id_ % config_.home_layers) continue;
    const Eigen::Vector2d away = here - Eigen::Vector2d(r.x_m, r.y_m);
    const double dist = away.norm();
    if (dist > 1e-3 && dist < kHomeSeparation_m)
      v += away / dist * kHomeSeparationSpeed_m_s * (1.0 - dist / kHomeSeparation_m);
  }
  return v;
}

}  // namespace uavsim::missions::coverage
