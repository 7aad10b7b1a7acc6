#include "fc/waypoint_nav.hpp"

#include <algorithm>
#include <cmath>

namespace uavsim::server::fc {

namespace {
// the carrot waits when the vehicle is further behind than this
constexpr double kLeashM = 6.0;
// within this distance and speed the carrot snaps onto the destination
constexpr double kSnapDistM = 1e-3;
constexpr double kSnapSpeedM_S = 0.05;

// the largest scalar limit along unit direction u for separate horizontal/up/down limits
double limit_along(const Eigen::Vector3d& u, double xy, double up, double dn) {
  double lim = 1e9;
  const double uxy = u.head<2>().norm();
  if (uxy > 1e-9) lim = std::min(lim, xy / uxy);
  if (u.z() > 1e-9) lim = std::min(lim, up / u.z());
  if (u.z() < -1e-9) lim = std::min(lim, dn / -u.z());
  return lim;
}
}  // namespace

void WaypointNav::start(const Eigen::Vector3d& position_enu_m,
                        const Eigen::Vector3d& velocity_enu_m_s,
                        const Eigen::Vector3d& destination_enu_m) {
  position_enu_m_ = position_enu_m;
  velocity_enu_m_s_ = velocity_enu_m_s;
  accel_enu_m_s2_.setZero();
  destination_enu_m_ = destination_enu_m;
  arrived_ = false;
}

void WaypointNav::update(double dt_s, const NavLimits& lim, const Eigen::Vector3d& vehicle_enu_m) {
  if (!(dt_s > 0.0)) return;
  const Eigen::Vector3d to_dest = destination_enu_m_ - position_enu_m_;
  const double dist = to_dest.norm();
  // desired carrot velocity: toward the destination, at the speed that can still stop on it
  Eigen::Vector3d vel_des = Eigen::Vector3d::Zero();
  double accel_max = std::min(lim.accel_xy_m_s2, lim.accel_z_m_s2);
  if (dist > kSnapDistM) {
    const Eigen::Vector3d u = to_dest / dist;
    const double v_max = limit_along(u, lim.speed_xy_m_s, lim.speed_up_m_s, lim.speed_dn_m_s);
    accel_max = limit_along(u, lim.accel_xy_m_s2, lim.accel_z_m_s2, lim.accel_z_m_s2);
    double speed = std::min(v_max, std::sqrt(2.0 * accel_max * dist));
    // a vehicle far behind holds the carrot back (ArduCopter's leash)
    if ((position_enu_m_ - vehicle_enu_m).norm() > kLeashM) speed = 0.0;
    vel_des = u * std::min(speed, dist / dt_s);
  }
  // change the carrot velocity horizontally by at most WPNAV_ACCEL * dt and vertically by at most
  // WPNAV_ACCEL_Z * dt, each part on its own: one shared budget let a long horizontal acceleration starve
  // the vertical correction, so a climb still under way when a level leg began (a goto issued at the
  // end of a take-off) carried on for seconds and overshot the leg's altitude by up to 1 m
  Eigen::Vector3d dv = vel_des - velocity_enu_m_s_;
  const double dv_xy_max = lim.accel_xy_m_s2 * dt_s;
  const double dv_z_max = lim.accel_z_m_s2 * dt_s;
  const double dv_xy = dv.head<2>().norm();
  if (dv_xy > dv_xy_max) dv.head<2>() *= dv_xy_max / dv_xy;
  dv.z() = std::clamp(dv.z(), -dv_z_max, dv_z_max);
  velocity_enu_m_s_ += dv;
  accel_enu_m_s2_ = dv / dt_s;
  position_enu_m_ += velocity_enu_m_s_ * dt_s;
  // arrival: snap when close and slow
  const double remaining = (destination_enu_m_ - position_enu_m_).norm();
  if (remaining < 0.01 && velocity_enu_m_s_.norm() < kSnapSpeedM_S) {
    position_enu_m_ = destination_enu_m_;
    velocity_enu_m_s_.setZero();
    accel_enu_m_s2_.setZero();
    arrived_ = true;
  } else {
    arrived_ = false;
  }
}

}  // namespace uavsim::server::fc
