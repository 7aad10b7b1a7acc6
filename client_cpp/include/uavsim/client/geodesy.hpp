// Local <-> geodetic conversion and the ENU/NED frame helpers for mission code: the project's one
// implementation (uavsim/common/geodesy.hpp, frames.hpp and angles.hpp, library uavsim::common),
// named in uavsim::client. The server converts with the same functions, so a mission and the
// simulator can never disagree about a position.
//
// The local frame is centred at the origin (lat0, lon0, alt0) and rotated by heading_rad about the
// vertical; with heading 0 the NED axes are north, east, down and the ENU axes east, north, up.
// Flat-earth approximation, good to centimetres within a few kilometres. With ArduCopter the origin
// is the EKF origin (GPS_GLOBAL_ORIGIN), which is what Vehicle::telemetry().origin holds.
//
// A default-constructed GeodeticOrigin is the server's default home (47.397742 N, 8.545594 E,
// 488 m, heading 0), the origin of every world that sets none of its own; a mission should still
// take the vehicle's own origin from its telemetry (origin_set), as a world and --home may move it.
#pragma once

#include <Eigen/Core>

#include "uavsim/common/angles.hpp"
#include "uavsim/common/frames.hpp"
#include "uavsim/common/geodesy.hpp"

namespace uavsim::client {

using common::Geodetic;
using common::GeodeticOrigin;

// Thread-safe (pure).
using common::enu_from_geodetic;
using common::geodetic_from_enu;
using common::geodetic_from_ned;
using common::ned_from_geodetic;

// NED <-> ENU (swap x/y, negate z); the same map both ways. Thread-safe (pure).
using common::frames::enu_from_ned;
using common::frames::ned_from_enu;

// An angle wrapped to (-pi, pi] in constant time; a non-finite angle gives 0. Thread-safe (pure).
using common::wrap_pi;

// Yaw angles: NED yaw is clockwise from north, ENU yaw counter-clockwise from east; the result is
// wrapped to (-pi, pi]. Thread-safe (pure).
inline double enu_yaw_from_ned(double ned_yaw_rad) {
  return common::frames::yaw_enu_from_yaw_ned(ned_yaw_rad);
}
inline double ned_yaw_from_enu(double enu_yaw_rad) {
  return common::frames::yaw_ned_from_yaw_enu(enu_yaw_rad);
}

}  // namespace uavsim::client
