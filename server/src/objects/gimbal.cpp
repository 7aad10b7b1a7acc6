#include "objects/gimbal.hpp"

#include <cmath>

#include "physics/object_bodies.hpp"

namespace uavsim::server::objects {

const char* gimbal_mode_name(GimbalMode mode) {
  switch (mode) {
    case GimbalMode::kDown: return "down";
    case GimbalMode::kForward: return "forward";
    case GimbalMode::kTargets: return "targets";
  }
  return "?";
}

Eigen::Quaterniond GimbalSet::pointing(const Gimbal& g, double vehicle_yaw_rad) {
  double pitch = 0.0, yaw = 0.0;
  switch (g.mode) {
    case GimbalMode::kDown: pitch = -M_PI / 2; break;
    case GimbalMode::kForward: break;
    case GimbalMode::kTargets: pitch = g.pitch_rad; yaw = g.yaw_rad; break;
  }
  // yaw about z, then pitch about the new y axis (pitch up = x towards +z = negative rotation about y)
  return Eigen::Quaterniond(Eigen::AngleAxisd(vehicle_yaw_rad + yaw, Eigen::Vector3d::UnitZ()) *
                            Eigen::AngleAxisd(-pitch, Eigen::Vector3d::UnitY()));
}

void GimbalSet::before_step(sim::Simulation& sim) {
  if (!initial_saved_) {
    initial_ = gimbals_;
    initial_saved_ = true;
  }
  for (const Gimbal& g : gimbals_) {
    const fc::TruthState t = sim.world().truth(static_cast<size_t>(g.vehicle));
    const Eigen::Vector3d x = t.q_enu_body * Eigen::Vector3d::UnitX();
    const double heading = std::atan2(x.y(), x.x());
    physics::set_mocap_pose(sim.world(), g.body_id, t.position_enu_m + t.q_enu_body * g.mount_body_m,
                            pointing(g, heading));
  }
}

void GimbalSet::reset(uint64_t /*seed*/) {
  if (initial_saved_) gimbals_ = initial_;
}

}  // namespace uavsim::server::objects
