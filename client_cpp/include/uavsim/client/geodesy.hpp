// Local <-> geodetic conversion for mission code (seed eq. 6.1), re-exported from the project's one
// implementation (uavsim/common/geodesy.hpp, target uavsim_common).
//
// The local frame is centred at the origin (lat0, lon0, alt0) and rotated by heading_rad about the vertical;
// with heading 0 the NED axes are north, east, down and the ENU axes east, north, up. Flat-earth
// approximation, good to centimetres within a few kilometres. With ArduCopter the origin is the EKF origin
// (GPS_GLOBAL_ORIGIN), which is what Vehicle::telemetry().origin holds.
#pragma once

#include <Eigen/Core>

namespace uavsim::client {

struct GeodeticOrigin {
  double lat_deg = 0.0;
  double lon_deg = 0.0;
  double alt_m = 0.0;        // above mean sea level
  double heading_rad = 0.0;  // rotation of the local frame; 0 = x north (NED)
};

struct Geodetic {
  double lat_deg = 0.0;
  double lon_deg = 0.0;
  double alt_m = 0.0;  // above mean sea level
};

// Thread-safe (pure).
Eigen::Vector3d ned_from_geodetic(const GeodeticOrigin& origin, const Geodetic& point);
Geodetic geodetic_from_ned(const GeodeticOrigin& origin, const Eigen::Vector3d& ned_m);
Eigen::Vector3d enu_from_geodetic(const GeodeticOrigin& origin, const Geodetic& point);
Geodetic geodetic_from_enu(const GeodeticOrigin& origin, const Eigen::Vector3d& enu_m);

// NED <-> ENU (swap x/y, negate z); the same function both ways.
inline Eigen::Vector3d enu_from_ned(const Eigen::Vector3d& v) { return {v.y(), v.x(), -v.z()}; }
inline Eigen::Vector3d ned_from_enu(const Eigen::Vector3d& v) { return {v.y(), v.x(), -v.z()}; }
// An angle wrapped to (-pi, pi] in constant time; a non-finite angle gives 0. Thread-safe (pure).
double wrap_pi(double a_rad);
// Yaw angles: NED yaw is clockwise from north, ENU yaw counter-clockwise from east.
double enu_yaw_from_ned(double ned_yaw_rad);
double ned_yaw_from_enu(double enu_yaw_rad);

}  // namespace uavsim::client
