#include "objects/gimbal.hpp"

#include <cmath>

#include "physics/object_bodies.hpp"
#include "uavsim/common/angles.hpp"

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
    case GimbalMode::kDown: pitch = -common::kPi / 2; break;
    case GimbalMode::kForward: break;
    case GimbalMode::kTargets: pitch = g.pitch_rad; yaw = g.yaw_rad; break;
  }
  // yaw about z, then pitch about the new y axis (pitch up = x towards +z = negative rotation about y)
  return Eigen::Quaterniond(Eigen::AngleAxisd(vehicle_yaw_rad + yaw, Eigen::Vector3d::UnitZ()) *
                            Eigen::AngleAxisd(-pitch, Eigen::Vector3d::UnitY()));
}

void step_gimbal_motion(const sim::GimbalDynamicsParams& p, const Eigen::Quaterniond& q_body_target, double dt_s,
                        GimbalMotion* m) {
  if (!m->started) {
    m->q_body_cam = q_body_target;
    m->rate_body_rad_s.setZero();
    m->started = true;
    return;
  }
  if (!(dt_s > 0)) return;
  // pointing error as a rotation vector in the body frame (the short way round)
  Eigen::Quaterniond q_err = q_body_target * m->q_body_cam.conjugate();
  if (q_err.w() < 0) q_err.coeffs() *= -1.0;
  const Eigen::AngleAxisd aa(q_err);
  const Eigen::Vector3d err_body_rad = aa.angle() * aa.axis();
  // first-order slew, rate-limited
  Eigen::Vector3d want_rad_s = p.time_const_s > 0 ? Eigen::Vector3d(err_body_rad / p.time_const_s)
                                                  : Eigen::Vector3d(err_body_rad / dt_s);
  if (p.rate_max_rad_s > 0 && want_rad_s.norm() > p.rate_max_rad_s) {
    want_rad_s *= p.rate_max_rad_s / want_rad_s.norm();
  }
  // acceleration-limited change of the slew rate
  Eigen::Vector3d change = want_rad_s - m->rate_body_rad_s;
  const double max_change = p.accel_max_rad_s2 * dt_s;
  if (p.accel_max_rad_s2 > 0 && change.norm() > max_change) change *= max_change / change.norm();
  m->rate_body_rad_s += change;
  // integrate: rotate by rate * dt about the body-frame axis
  const Eigen::Vector3d turn = m->rate_body_rad_s * dt_s;
  if (turn.norm() > 0) {
    m->q_body_cam = (Eigen::Quaterniond(Eigen::AngleAxisd(turn.norm(), turn.normalized())) * m->q_body_cam).normalized();
  }
}

double GimbalSet::heading(const Eigen::Quaterniond& q_enu_body) {
  const Eigen::Vector3d x = q_enu_body * Eigen::Vector3d::UnitX();
  return std::atan2(x.y(), x.x());
}

Eigen::Quaterniond GimbalSet::actual(const Gimbal& g, const Eigen::Quaterniond& q_enu_body) {
  return (q_enu_body * g.motion.q_body_cam).normalized();
}

Eigen::Quaterniond GimbalSet::orientation(const Gimbal& g, const Eigen::Quaterniond& q_enu_body) {
  return g.motion.started ? actual(g, q_enu_body) : pointing(g, heading(q_enu_body));
}

void GimbalSet::before_step(sim::Simulation& sim) {
  if (!initial_saved_) {
    initial_ = gimbals_;
    initial_saved_ = true;
  }
  const bool dynamic = dynamics_.time_const_s > 0 || dynamics_.rate_max_rad_s > 0 || dynamics_.accel_max_rad_s2 > 0;
  const double now_s = sim.time_s();
  for (Gimbal& g : gimbals_) {
    const fc::TruthState t = sim.world().truth(static_cast<size_t>(g.vehicle));
    if (dynamic) {
      // the camera rides on the body; the loop slews it towards the target, once a physics step
      const double dt_s = g.motion.started ? now_s - g.motion.time_s : 0.0;
      step_gimbal_motion(dynamics_, t.q_enu_body.conjugate() * pointing(g, heading(t.q_enu_body)),
                         dt_s, &g.motion);
      g.motion.time_s = now_s;
    }
    place(sim, g, t);
  }
}

void GimbalSet::place(sim::Simulation& sim) const {
  for (const Gimbal& g : gimbals_) place(sim, g, sim.world().truth(static_cast<size_t>(g.vehicle)));
}

void GimbalSet::place(sim::Simulation& sim, const Gimbal& g, const fc::TruthState& t) {
  physics::set_mocap_pose(sim.world(), g.body_id, t.position_enu_m + t.q_enu_body * g.mount_body_m,
                          orientation(g, t.q_enu_body));
}

void GimbalSet::schedule_capture_pose(sim::Simulation& sim) {
  sim.schedule().add(
      sim::Phase::kCapture, "gimbals.pose", [this, &sim] { place(sim); }, sim::Slot::kFirst);
}

void GimbalSet::reset(uint64_t /*seed*/) {
  if (initial_saved_) gimbals_ = initial_;
  for (Gimbal& g : gimbals_) g.motion = GimbalMotion{};
}

}  // namespace uavsim::server::objects
