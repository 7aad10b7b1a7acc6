#include "agent.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "agent_tuning.hpp"

namespace uavsim::missions::coverage {

using namespace agent_tuning;  // the agent's own constants, unqualified

const char* agent_state_name(AgentState s) {
  switch (s) {
    case AgentState::kTakingOff:
      return "Taking Off";
    case AgentState::kQuerying:
      return "Querying";
    case AgentState::kDeploying:
      return "Deploying";
    case AgentState::kRunning:
      return "Running";
    case AgentState::kWaiting:
      return "Waiting";
    case AgentState::kNonLeader:
      return "Non-Leader";
    case AgentState::kGoingHome:
      return "Going Home";
    case AgentState::kLanded:
      return "Landed";
    case AgentState::kFailed:
      return "Failed";
  }
  return "?";
}

Agent::Agent(const CoverageConfig& config, int id, const Eigen::Vector2d& home_enu_m,
             const FrameFit& frames)
    : config_(config),
      id_(id),
      home_enu_m_(home_enu_m),
      origin_{config.origin_x_m, config.origin_y_m},
      frames_(frames),
      adb_(id,
           [base = config.max_age_base_s, per_hop = config.max_age_per_hop_s](int hops) {
             return static_cast<int>(1000.0 * (base + per_hop * std::max(hops, 0)));
           }),
      own_(config.stripe_count()),
      aggregation_(id, config.stripe_count()),
      reassembler_(config.stripe_count()),
      flock_(config.gains),
      aggregate_pacer_(kAggregateAirtimeShare, kAggregateBurst_s, frames.max_frame_bytes) {}

bool Agent::is_leader_state() const {
  return state_ == AgentState::kQuerying || state_ == AgentState::kDeploying ||
         state_ == AgentState::kRunning || state_ == AgentState::kWaiting;
}

void Agent::enter(AgentState s, AgentOutputs& out, const std::string& why) {
  if (!out.note.empty()) out.note += "; ";
  out.note += std::string(agent_state_name(state_)) + " -> " + agent_state_name(s);
  if (!why.empty()) out.note += " (" + why + ")";
  state_ = s;
  state_since_s_ = last_now_s_;
  rewind_hold_ = rewind_back_ = false;
  if (s == AgentState::kGoingHome) home_round_ = round_;
}

bool Agent::descending_when_disarmed(const AgentInputs& in) const {
  // A landing ends with the autopilot's land detector: the vehicle has stopped on the ground
  // before it disarms. The autopilot reports "on the ground" at any disarm, so a disarm seen while
  // the vehicle is still metres up or still sinking is a failure, not a touchdown.
  constexpr double kLandedMaxHeight_m = 1.0;      // above the take-off spot (estimate drift, gear)
  constexpr double kLandedMaxSinkRate_m_s = 0.5;  // half the final descent speed (LAND_SPEED)
  return in.position_enu_m.z() - ground_z_m_ > kLandedMaxHeight_m ||
         in.velocity_enu_m_s.z() < -kLandedMaxSinkRate_m_s;
}

AgentOutputs Agent::step(const AgentInputs& in) {
  AgentOutputs out;
  // time: ages advance by the elapsed milliseconds (Algorithm 2 runs every millisecond)
  const double dt = started_ ? std::max(0.0, in.now_s - last_now_s_) : 0.0;
  if (!started_) {
    started_ = true;
    state_since_s_ = in.now_s;
    next_beacon_s_ = in.now_s;
  }
  time_in_state_[static_cast<size_t>(state_)] += dt;
  dt_s_ = dt;
  last_now_s_ = in.now_s;
  age_remainder_ms_ += dt * 1000.0;
  const int elapsed_ms = static_cast<int>(age_remainder_ms_);
  age_remainder_ms_ -= elapsed_ms;
  if (elapsed_ms > 0) {
    // an agent that aged out on the way home, not known to have landed, died with its pictures
    // (on the ground too, in our own round: the last agents flying may die after we landed; in a
    // later round its flyers may just be out of range, surveying)
    for (int id : adb_.age(elapsed_ms)) {
      if (landed_ids_.count(id)) continue;
      // Running: its last record tells where and how long ago it died
      if (state_ == AgentState::kRunning && path_) start_rewind(in, *adb_.evicted(id));
      const bool landed_here = state_ == AgentState::kLanded && no_later_round_surveying();
      if (state_ != AgentState::kGoingHome && !landed_here) continue;
      if (!loss_pending_) loss_since_s_ = in.now_s;
      loss_pending_ = true;
    }
  }

  if (state_ == AgentState::kFailed) return out;
  if (state_ == AgentState::kLanded) {
    // on the ground the radio stays on: the agent still relays, beacons (landed) and answers the
    // leader's queries, since its pictures are part of the flock's map
    receive(in);
    // a loss noticed on the ground: when no agent that flies is left to check it, the lowest id
    // landed checks the flock's map, and takes off again if the rectangle is no longer covered
    // (verify_after_loss); the others stay on for its query a while
    if (loss_pending_ && adb_.leader() != id_ && in.now_s - loss_since_s_ > kLossWait_s)
      loss_pending_ = false;
    if (loss_pending_ && verify_after_loss(in, out)) return out;
    const bool quiet = adb_.all_landed() && no_later_round_surveying() && !loss_pending_;
    if (!quiet)
      all_landed_since_s_ = -1.0;
    else if (all_landed_since_s_ < 0.0)
      all_landed_since_s_ = in.now_s;
    broadcast(in, out);
    return out;
  }
  // our own vehicle stopped flying in the air: a dead drone is silent
  // (Going Home ends disarmed on the ground once it has sent the landing; before that, a disarm
  // is a failure too)
  if (airborne_seen_ && !in.armed && (state_ != AgentState::kGoingHome || !land_sent_)) {
    enter(AgentState::kFailed, out, "vehicle disarmed in flight");
    return out;
  }
  if (in.armed && !in.on_ground) airborne_seen_ = true;
  if (!airborne_seen_ && in.on_ground) ground_z_m_ = in.position_enu_m.z();

  receive(in);
  take_picture(in, out);
  run_state(in, out);
  if (state_ != AgentState::kLanded) broadcast(in, out);
  return out;
}

void Agent::start_rewind(const AgentInputs& in, const AgentRecord& lost) {
  // Only while the station's map keeps arriving: there the lost agent's pictures survive and the
  // open strip is all that is missing. In the plain variant its pictures of the pass die with it,
  // the recovery flies its whole strip again, open stretch included, and a rewind is time lost (25
  // quads, p 0.001, seed 1: 2340.1 s with it against 1776.9 s without, the longer mission drawing
  // one failure more).
  if (in.now_s - gcs_map_at_s_ > kStationMapFresh_s) return;
  // where the lost agent flew across the line, against the flock's edges (the others and us)
  const Eigen::Vector2d across(-std::sin(target_heading_rad_), std::cos(target_heading_rad_));
  const Eigen::Vector2d here = in.position_enu_m.head<2>();
  const double at = across.dot(Eigen::Vector2d(lost.x_m, lost.y_m) - here);
  double low = std::min(0.0, at), high = std::max(0.0, at);
  for (const auto& [id, r] : adb_.records()) {
    if (r.landed) continue;
    const double a = across.dot(Eigen::Vector2d(r.x_m, r.y_m) - here);
    low = std::min(low, a);
    high = std::max(high, a);
  }
  if (std::min(at - low, high - at) <= config_.lateral_threshold_m) return;
  // the longest it can have been dead: the age allowed at its distance, and a beacon period
  const double dead_s = config_.max_age_base_s + config_.max_age_per_hop_s * lost.distance_hops +
                        1.0 / config_.broadcast_hz;
  const double dir = path_x_direction(*path_);
  const double back_m = std::min(dead_s * config_.cruise_speed_m_s + kRewindMargin_m,
                                 std::abs(in.position_enu_m.x() - path_->points_enu_m.front().x()));
  if (!rewind_hold_ && !rewind_back_) rewind_x_m_ = in.position_enu_m.x() - dir * back_m;
  rewind_hold_ = true;
  rewind_back_ = false;
  rewind_since_s_ = in.now_s;
}

void Agent::receive(const AgentInputs& in) {
  if (in.gcs_map && in.gcs_map->stripe_count() == own_.stripe_count()) {
    gcs_map_ = in.gcs_map;
    gcs_map_at_s_ = in.now_s;
  }
  for (const Frame& f : in.received) {
    const auto type = message_type(f);
    if (type == MessageType::kBeacon) {
      if (!decode_beacon(f, origin_, &heard_)) continue;
      const Beacon* b = &heard_;
      adb_.on_message(b->self, b->records);
      // a later survey round: a recall after a loss on the way home, or its going home
      const int ahead = (b->round - round_ + kRounds) % kRounds;
      if (ahead != 0 && ahead < kRounds / 2) {
        round_ = b->round;
        going_home_heard_ = false;
        recalled_ = !b->going_home;
      }
      if (b->round == round_ && b->going_home) going_home_heard_ = true;
      // a round that surveys on after we landed: one of its surveying flyers heard to have landed
      // means it is over (its leader lands last, once every agent it hears has landed); agents
      // still landing from our round are homebound, not its flyers
      if (state_ == AgentState::kLanded && round_ != home_round_ && b->round == round_) {
        if (!b->self.landed && !b->homebound) {
          later_round_flyers_.insert(b->self.id);
        } else if (later_round_flyers_.count(b->self.id)) {
          later_round_over_ = true;
        }
      }
    } else if (type == MessageType::kAggregate) {
      if (auto m = reassembler_.add(f)) aggregation_.on_message(*m, adb_.leader(), own_);
    }
  }
  for (const auto& [id, r] : adb_.records())
    if (r.landed) landed_ids_.insert(id);
}

void Agent::take_picture(const AgentInputs& in, AgentOutputs& out) {
  if (state_ == AgentState::kTakingOff || state_ == AgentState::kGoingHome) return;
  const auto p = camera_trigger(config_, in.position_enu_m.x(), in.position_enu_m.y(),
                                in.position_enu_m.z(), in.yaw_enu_rad, own_);
  if (!p) return;
  own_.add(p->stripe, p->covered);
  aggregation_.refresh_own(own_);
  out.picture = p;
}

void Agent::broadcast(const AgentInputs& in, AgentOutputs& out) {
  if (in.now_s >= next_beacon_s_) {
    // catch up without bursts if the caller stepped slowly
    next_beacon_s_ = std::max(next_beacon_s_ + 1.0 / config_.broadcast_hz, in.now_s);
    Beacon b;
    b.self.id = id_;
    b.self.seq = ++seq_;
    b.self.x_m = in.position_enu_m.x();
    b.self.y_m = in.position_enu_m.y();
    b.self.heading_rad = target_heading_rad_;
    b.self.vx_m_s = commanded_velocity_enu_m_s_.x();
    b.self.vy_m_s = commanded_velocity_enu_m_s_.y();
    b.self.landed = state_ == AgentState::kLanded;
    // an agent still landing from an earlier round does not send a later round's flock home
    b.going_home = state_ == AgentState::kGoingHome && home_round_ == round_;
    b.round = static_cast<uint8_t>(round_);
    b.homebound = state_ == AgentState::kGoingHome;
    // the next window of the ADB (rotating, so every record goes out in turn)
    const auto& records = adb_.records();
    if (!records.empty()) {
      record_cursor_ %= records.size();
      auto it = std::next(records.begin(), static_cast<long>(record_cursor_));
      const size_t window = std::min(
          records.size(),
          static_cast<size_t>(std::clamp(frames_.beacon_records, 1, kMaxRecordsPerBeacon)));
      for (size_t k = 0; k < window; ++k) {
        b.records.push_back(it->second);
        if (++it == records.end()) it = records.begin();
      }
      record_cursor_ += b.records.size();
    }
    out.broadcast.push_back(encode_beacon(b, origin_, frames_));
  }
  // aggregation messages after the beacon, paced (radio_pacer.hpp): the next copy only once the
  // last one has gone out
  if (aggregate_pacer_.idle()) {
    if (aggregation_.poll(in.now_s, adb_.neighbours(), config_.query_retransmit_s, &outgoing_))
      aggregate_pacer_.push(encode_aggregate(outgoing_, frames_));
  }
  for (Frame& f : aggregate_pacer_.take(dt_s_)) out.broadcast.push_back(std::move(f));
}

double Agent::altitude_rate(const AgentInputs& in, double altitude_m) const {
  return saturate(kAltitudeGain_1_s * (altitude_m - in.position_enu_m.z()), kMaxClimb_m_s);
}

double Agent::yaw_rate_to(const AgentInputs& in, double heading_rad) const {
  // R2's law, also for the leader's own turns
  return saturate(config_.gains.kp_r2 * angle_diff(heading_rad, in.yaw_enu_rad),
                  config_.gains.s_r2_deg_s * kPi / 180.0);
}

void Agent::fly_to(const AgentInputs& in, const Eigen::Vector2d& target, double speed,
                   double heading_rad, AgentOutputs& out) const {
  const Eigen::Vector2d d = target - in.position_enu_m.head<2>();
  const double dist = d.norm();
  Eigen::Vector2d v = Eigen::Vector2d::Zero();
  if (dist > 1e-6) v = d / dist * std::min(speed, kApproachGain_1_s * dist);
  out.action = AgentOutputs::Action::kVelocity;
  out.velocity_enu_m_s << v, altitude_rate(in, config_.altitude_m);
  out.yaw_rate_rad_s = yaw_rate_to(in, heading_rad);
  out.yaw_enu_rad = heading_rad;
}

bool Agent::flock_in_line(const AgentInputs& in) const {
  // every agent of the ADB within the tolerance of the leader's flock line (along the heading), and
  // no two neighbours along the line further apart than a footprint less kMinFootprintOverlap_m
  const Eigen::Vector2d dir(std::cos(target_heading_rad_), std::sin(target_heading_rad_));
  const Eigen::Vector2d across(-dir.y(), dir.x());
  std::vector<double> along_line{0.0};  // ourselves
  for (const auto& [id, r] : adb_.records()) {
    if (r.landed || id == id_) continue;  // on the ground at home, not part of the formation
    const Eigen::Vector2d d(r.x_m - in.position_enu_m.x(), r.y_m - in.position_enu_m.y());
    if (std::abs(d.dot(dir)) > config_.formation_tolerance_m) return false;
    along_line.push_back(d.dot(across));
  }
  std::sort(along_line.begin(), along_line.end());
  for (size_t i = 1; i < along_line.size(); ++i)
    if (along_line[i] - along_line[i - 1] > config_.y_sensor_m - kMinFootprintOverlap_m)
      return false;
  return true;
}

void Agent::start_query(AgentOutputs& out) {
  ++query_counter_;
  ++queries_started_;
  aggregation_.start(query_counter_, own_);
  if (!out.note.empty()) out.note += "; ";
  out.note += "query " + std::to_string(query_counter_) + " started";
}

AreaParts Agent::flock_map() const {
  // the query's result, with our own latest pictures and the ground station's map (3.6)
  AreaParts map = aggregation_.result();
  map.merge(own_);
  if (gcs_map_) map.merge(*gcs_map_);
  return map;
}

void Agent::finish_query(const AgentInputs& in, AgentOutputs& out) {
  AreaParts map = flock_map();
  // flying alone after taking off again: the landed agents keep their pictures (a landed drone
  // does not fail), but a query from the far end of the rectangle no longer reaches them
  if (landed_map_ && adb_.all_landed()) map.merge(*landed_map_);
  last_map_ = map;
  const double fraction = map.covered_fraction(config_.width_y_m);
  if (map.covers_all(config_.width_y_m)) {
    complete_ = true;
    enter(AgentState::kGoingHome, out, "rectangle covered");
    return;
  }
  std::vector<double> others_y;
  for (const auto& [id, r] : adb_.records())
    if (!r.landed) others_y.push_back(r.y_m);
  const FlockExtent extent = flock_extent(in.position_enu_m.y(), others_y, config_.gains.d_r1_m);
  // a path that covered (almost) nothing: plan the other side. The nearer side is the thesis's
  // rule, but a sliver left along the flock's far edge, where the outermost agent sits a metre or
  // two off the extent the leader measured, is missed pass after pass (5 quads over 600 x 600 m
  // flew the same 500 m path at 99.9 % until the 5000 s budget); planned from the other side, the
  // sliver lies under the leader's own footprint, on its own track.
  std::optional<PlannedPath> next;
  if (path_ && fraction < planned_fraction_ + kNoProgressFraction) {
    next = plan_side(config_, map, in.position_enu_m.head<2>(), extent, !path_->low_side);
  }
  if (!next) next = plan_path(config_, map, in.position_enu_m.head<2>(), extent);
  path_ = next;
  planned_fraction_ = fraction;
  if (!path_) {
    complete_ = true;
    enter(AgentState::kGoingHome, out, "nothing left to plan");
    return;
  }
  target_heading_rad_ = path_->heading_rad;
  enter(AgentState::kDeploying, out,
        fmt("covered %.1f%%, path from (%.1f, %.1f)", 100.0 * fraction,
            path_->points_enu_m.front().x(), path_->points_enu_m.front().y()) +
            (path_->low_side ? " on the low-y frontier" : " on the high-y frontier"));
}

bool Agent::verify_after_loss(const AgentInputs& in, AgentOutputs& out) {
  // Beyond the thesis (whose mission ends at the going-home broadcast): an agent that dies on the
  // way home takes the pictures only it held. The leader (the lowest id still flying) asks the
  // flock for its map again, and if the rectangle is no longer covered, starts the next survey
  // round: the agents still flying come back and the frontier is planned over what was lost. When
  // the last agents flying die after the others landed, the lowest id landed checks from the ground
  // and takes off again itself (the others, landed, keep their pictures and answer its queries).
  if (!loss_pending_ || adb_.leader() != id_) return false;
  const double now = in.now_s;
  if (!verifying_) {
    // with agents landed, ask near home, where they hear us; before any landed, at once
    if (!landed_ids_.empty() &&
        (home_enu_m_ - in.position_enu_m.head<2>()).norm() > kVerifyNearHome_m)
      return false;
    verifying_ = true;
    verify_since_s_ = now;
    start_query(out);
    out.note += " (a loss on the way home)";
    return false;
  }
  if (!aggregation_.complete(adb_.live_mask())) {
    if (now - verify_since_s_ > kQueryTimeout_s) {
      verify_since_s_ = now;
      start_query(out);
    }
    return false;
  }
  verifying_ = false;
  loss_pending_ = false;
  if (flock_map().covers_all(config_.width_y_m)) {
    if (!out.note.empty()) out.note += "; ";
    out.note += "the flock still holds the whole rectangle";
    return false;
  }
  round_ = (round_ + 1) % kRounds;
  going_home_heard_ = false;
  complete_ = false;
  path_.reset();
  flock_.reset();
  if (state_ == AgentState::kLanded) {
    // nobody left flying: take off again; once up, as the lowest id flying, it queries and plans.
    // What the landed agents hold now stays held: merged into every query's result while they are
    // the only others (finish_query)
    landed_map_ = flock_map();
    takeoff_sent_ = false;
    land_sent_ = false;
    airborne_seen_ = false;
    adb_.set_local_landed(false);
    later_round_flyers_.clear();
    later_round_over_ = false;
    all_landed_since_s_ = -1.0;
    enter(AgentState::kTakingOff, out, "pictures lost after the others landed: taking off again");
    out.note += " (recall: round " + std::to_string(round_) + ")";
    return true;
  }
  finish_query(in, out);  // plans over the gaps (Deploying)
  out.note += " (recall: round " + std::to_string(round_) + ")";
  return true;
}

}  // namespace uavsim::missions::coverage
