#include "app/gimbal_bridge.hpp"

#include <algorithm>
#include <cmath>

#include "uavsim/common/angles.hpp"
#include "uavsim/common/frames.hpp"

namespace uavsim::server::app {

namespace {
using common::kDegToRad;
using common::wrap_pi;
namespace frames = common::frames;
using common::mavlink::MavMountMode;

// RETRACT and NEUTRAL: level and straight ahead
bool mount_at_rest(std::uint8_t mount_mode) {
  return common::mavlink::is_one_of<MavMountMode>(mount_mode, {MavMountMode::Retract, MavMountMode::Neutral});
}
}  // namespace

std::optional<mavlink::GimbalDeviceAttitude> gimbal_device_attitude(
    const objects::GimbalSet& gimbals, sim::Simulation& sim, size_t vehicle) {
  for (const objects::Gimbal& g : gimbals.gimbals()) {
    if (g.vehicle != static_cast<int>(vehicle)) continue;
    const fc::TruthState t = sim.world().truth(vehicle);
    // the camera body's x axis is the optical axis, z up when level (FLU-like): its FRD attitude in
    // NED, turned back by the vehicle's heading
    const Eigen::Quaterniond q_ned_cam =
        frames::q_ned_frd_from_q_enu_flu(objects::GimbalSet::orientation(g, t.q_enu_body));
    const double heading_rad =
        frames::euler_from_q_ned_frd(frames::q_ned_frd_from_q_enu_flu(t.q_enu_body)).yaw_rad;
    const frames::Euler e = frames::euler_from_q_ned_frd(
        Eigen::AngleAxisd(-heading_rad, Eigen::Vector3d::UnitZ()) * q_ned_cam);
    return mavlink::GimbalDeviceAttitude{e.roll_rad / kDegToRad, e.pitch_rad / kDegToRad,
                                         e.yaw_rad / kDegToRad};
  }
  return std::nullopt;
}

void apply_gimbal_state(const mavlink::GimbalState& s, double vehicle_yaw_enu_rad, objects::Gimbal* g) {
  if (mount_at_rest(s.mount_mode)) {
    g->mode = objects::GimbalMode::kForward;
    g->pitch_rad = 0.0;
    g->yaw_rad = 0.0;
    return;
  }
  g->mode = objects::GimbalMode::kTargets;
  g->pitch_rad = std::clamp(s.pitch_deg, -90.0, 90.0) * kDegToRad;
  if (s.yaw_earth_frame) {
    // a heading (clockwise from north) -> ENU yaw -> relative to the vehicle, counter-clockwise
    const double enu_yaw = (90.0 - s.yaw_deg) * kDegToRad;
    g->yaw_rad = wrap_pi(enu_yaw - vehicle_yaw_enu_rad);
  } else {
    g->yaw_rad = wrap_pi(-s.yaw_deg * kDegToRad);
  }
}

MavlinkGimbalBridge::MavlinkGimbalBridge(objects::GimbalSet& gimbals, StateOf state_of)
    : gimbals_(gimbals), state_of_(std::move(state_of)), applied_stamp_(gimbals.gimbals().size(), -1.0) {}

void MavlinkGimbalBridge::update(sim::Simulation& sim) {
  std::vector<objects::Gimbal>& all = gimbals_.gimbals();
  for (size_t k = 0; k < all.size(); ++k) {
    objects::Gimbal& g = all[k];
    if (g.vehicle < 0 || static_cast<size_t>(g.vehicle) >= sim.vehicle_count()) continue;
    const mavlink::GimbalState& s = state_of_(static_cast<size_t>(g.vehicle));
    if (s.stamp_s < 0) continue;  // never commanded: the world's mode stays
    const bool fresh = s.stamp_s != applied_stamp_[k];
    // an earth-frame yaw is held while the vehicle turns: re-apply it every step
    const bool held = s.yaw_earth_frame && !mount_at_rest(s.mount_mode) && g.mode == objects::GimbalMode::kTargets;
    if (!fresh && !held) continue;
    const fc::TruthState t = sim.world().truth(static_cast<size_t>(g.vehicle));
    const Eigen::Vector3d x = t.q_enu_body * Eigen::Vector3d::UnitX();
    apply_gimbal_state(s, std::atan2(x.y(), x.x()), &g);
    applied_stamp_[k] = s.stamp_s;
  }
}

}  // namespace uavsim::server::app
