// Waypoint navigation (ArduCopter AC_WPNav's role): a target point (the "carrot") travels from where it
// starts to the destination along a straight line with limited speed and acceleration (horizontal
// WPNAV_SPEED/WPNAV_ACCEL, vertical WPNAV_SPEED_UP/DN and WPNAV_ACCEL_Z), decelerating so it stops on
// the destination. The position controller chases the carrot with its velocity and acceleration as
// feed-forward, so a 20 m step becomes a smooth trajectory instead of a saturated lunge.
#pragma once

#include <Eigen/Core>

namespace uavsim::server::fc {

struct NavLimits {
  double speed_xy_m_s = 10.0;
  double speed_up_m_s = 2.5;
  double speed_dn_m_s = 1.5;
  double accel_xy_m_s2 = 2.5;
  double accel_z_m_s2 = 1.0;
};

class WaypointNav {
 public:
  // Starts the carrot at position/velocity and aims it at destination.
  void start(const Eigen::Vector3d& position_enu_m, const Eigen::Vector3d& velocity_enu_m_s,
             const Eigen::Vector3d& destination_enu_m);
  // Changes the destination, keeping the carrot's state (no jump).
  void set_destination(const Eigen::Vector3d& destination_enu_m) { destination_enu_m_ = destination_enu_m; }
  // (dt, limits, vehicle position) => carrot moved; it waits when the vehicle trails by > leash.
  void update(double dt_s, const NavLimits& limits, const Eigen::Vector3d& vehicle_enu_m);

  const Eigen::Vector3d& position() const { return position_enu_m_; }
  const Eigen::Vector3d& velocity() const { return velocity_enu_m_s_; }
  const Eigen::Vector3d& accel() const { return accel_enu_m_s2_; }
  const Eigen::Vector3d& destination() const { return destination_enu_m_; }
  // The carrot sits on the destination.
  bool arrived() const { return arrived_; }

 private:
  Eigen::Vector3d position_enu_m_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d velocity_enu_m_s_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d accel_enu_m_s2_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d destination_enu_m_ = Eigen::Vector3d::Zero();
  bool arrived_ = true;
};

}  // namespace uavsim::server::fc
