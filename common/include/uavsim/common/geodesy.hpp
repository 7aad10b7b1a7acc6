// Local <-> geodetic conversion, the one place it happens (eq. 6.1 of the thesis the project
// descends from). Pure functions, for the server's endpoint and the client, which names them in
// uavsim::client.
//
// Seed eq. (6.1): the local frame is centred at (lat0, lon0, alt0) and rotated by hdg0 about the
// vertical:
//   [x y z]^T = Rz(hdg0) * [ R (lat - lat0),  R (lon - lon0) cos(lat0),  alt0 - alt ]^T,
//   Rz(h) = [[cos h, sin h, 0], [-sin h, cos h, 0], [0, 0, 1]],  R = 6378100 m (equatorial radius),
// angles in radians. With hdg0 = 0 the result is north-east-down (the MAVLink local frame). It is a
// flat-earth approximation, good to a few centimetres within a few kilometres of the origin.
#pragma once

#include <Eigen/Core>

namespace uavsim::common {

inline constexpr double kEarthRadiusM = 6378100.0;  // seed eq. (6.1) footnote

// The geodetic position of the local origin (the MuJoCo world origin = EKF origin of every vehicle).
// Default: the PX4/Gazebo Zurich test site (47.397742 N, 8.545594 E, 488 m AMSL); a world sets its own
// (custom numeric uavsim:home) and uavsim-server --home overrides both (ArduPilot SITL's CMAC location is
// -35.363261,149.165230,584).
struct GeodeticOrigin {
  double lat_deg = 47.397742;
  double lon_deg = 8.545594;
  double alt_m = 488.0;       // above mean sea level
  double heading_rad = 0.0;   // hdg0 of eq. (6.1); 0 = local x points north
};

struct Geodetic {
  double lat_deg = 0.0;
  double lon_deg = 0.0;
  double alt_m = 0.0;  // above mean sea level
};

// lla2xyz of eq. (6.1): geodetic => local north-east-down metres (rotated by the origin's heading).
// Thread-safe (pure).
Eigen::Vector3d ned_from_geodetic(const GeodeticOrigin& origin, const Geodetic& point);

// xyz2lla, the inverse of ned_from_geodetic(). Thread-safe (pure).
Geodetic geodetic_from_ned(const GeodeticOrigin& origin, const Eigen::Vector3d& ned_m);

// The same two in the simulator's ENU frame (the NED result through frames::enu_from_ned): with
// heading 0, x east, y north, z up. Thread-safe (pure).
Eigen::Vector3d enu_from_geodetic(const GeodeticOrigin& origin, const Geodetic& point);
Geodetic geodetic_from_enu(const GeodeticOrigin& origin, const Eigen::Vector3d& enu_m);

}  // namespace uavsim::common
