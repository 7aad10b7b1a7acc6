// The ranges the MAVLink edge accepts before a value reaches the flight controller. Anything outside is
// refused (COMMAND_ACK DENIED, MISSION_ACK ERROR, setpoint counted in rejected_inputs), so the controller
// only ever sees finite values of a size a real vehicle could be asked for.
#pragma once

#include <Eigen/Core>

#include "sim/checked_number.hpp"
#include "uavsim/common/angles.hpp"

namespace uavsim::server::mavlink::limits {

inline constexpr double kPosition_m = 1e5;      // local setpoints, altitudes: 100 km covers any world
inline constexpr double kSpeed_m_s = 1000.0;    // far beyond any copter, small enough for the controllers
inline constexpr double kAccel_m_s2 = 1000.0;
inline constexpr double kYaw_rad = 4.0 * common::kPi;  // headings come as [-pi, pi] or [0, 2pi]
inline constexpr double kRate_rad_s = 35.0;     // about 2000 deg/s, a MEMS gyro's full scale
inline constexpr double kAngle_deg = 360.0;     // CONDITION_YAW angle, gimbal angles
inline constexpr double kYawRate_deg_s = 2000.0;
inline constexpr double kDuration_s = 86400.0;  // hold / loiter times

// |v| <= limit and finite.
inline bool within(double v, double limit) { return sim::finite_in(v, -limit, limit); }
inline bool within(const Eigen::Vector3d& v, double limit) {
  return within(v.x(), limit) && within(v.y(), limit) && within(v.z(), limit);
}
// A latitude/longitude pair in degrees.
inline bool valid_lat_lon(double lat_deg, double lon_deg) { return within(lat_deg, 90.0) && within(lon_deg, 180.0); }

}  // namespace uavsim::server::mavlink::limits
