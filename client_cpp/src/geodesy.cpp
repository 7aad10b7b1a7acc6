#include "uavsim/client/geodesy.hpp"

#include <cmath>

#include "uavsim/common/angles.hpp"
#include "uavsim/common/geodesy.hpp"

namespace uavsim::client {

namespace {
namespace g = common;
g::GeodeticOrigin to_server(const GeodeticOrigin& o) { return {o.lat_deg, o.lon_deg, o.alt_m, o.heading_rad}; }
}  // namespace

double wrap_pi(double a_rad) { return common::wrap_pi(a_rad); }

Eigen::Vector3d ned_from_geodetic(const GeodeticOrigin& origin, const Geodetic& point) {
  return g::ned_from_geodetic(to_server(origin), g::Geodetic{point.lat_deg, point.lon_deg, point.alt_m});
}

Geodetic geodetic_from_ned(const GeodeticOrigin& origin, const Eigen::Vector3d& ned_m) {
  const g::Geodetic r = g::geodetic_from_ned(to_server(origin), ned_m);
  return {r.lat_deg, r.lon_deg, r.alt_m};
}

Eigen::Vector3d enu_from_geodetic(const GeodeticOrigin& origin, const Geodetic& point) {
  return enu_from_ned(ned_from_geodetic(origin, point));
}

Geodetic geodetic_from_enu(const GeodeticOrigin& origin, const Eigen::Vector3d& enu_m) {
  return geodetic_from_ned(origin, ned_from_enu(enu_m));
}

double enu_yaw_from_ned(double ned_yaw_rad) { return wrap_pi(common::kPi / 2.0 - ned_yaw_rad); }
double ned_yaw_from_enu(double enu_yaw_rad) { return wrap_pi(common::kPi / 2.0 - enu_yaw_rad); }

}  // namespace uavsim::client
