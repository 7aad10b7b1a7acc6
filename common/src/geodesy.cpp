#include "uavsim/common/geodesy.hpp"

#include <cmath>

#include "uavsim/common/angles.hpp"
#include "uavsim/common/frames.hpp"

namespace uavsim::common {

Eigen::Vector3d ned_from_geodetic(const GeodeticOrigin& origin, const Geodetic& point) {
  // unrotated local offsets: R*dlat, R*dlon*cos(lat0), alt0 - alt
  const double lat0 = origin.lat_deg * kDegToRad;
  const double n = kEarthRadiusM * (point.lat_deg - origin.lat_deg) * kDegToRad;
  const double e = kEarthRadiusM * (point.lon_deg - origin.lon_deg) * kDegToRad * std::cos(lat0);
  const double d = origin.alt_m - point.alt_m;
  // rotate by hdg0 about the vertical
  const double c = std::cos(origin.heading_rad), s = std::sin(origin.heading_rad);
  return {c * n + s * e, -s * n + c * e, d};
}

Geodetic geodetic_from_ned(const GeodeticOrigin& origin, const Eigen::Vector3d& ned_m) {
  // undo the heading rotation (Rz is orthonormal: inverse = transpose)
  const double c = std::cos(origin.heading_rad), s = std::sin(origin.heading_rad);
  const double n = c * ned_m.x() - s * ned_m.y();
  const double e = s * ned_m.x() + c * ned_m.y();
  // undo the scaling
  const double lat0 = origin.lat_deg * kDegToRad;
  Geodetic g;
  g.lat_deg = origin.lat_deg + n / kEarthRadiusM / kDegToRad;
  g.lon_deg = origin.lon_deg + e / (kEarthRadiusM * std::cos(lat0)) / kDegToRad;
  g.alt_m = origin.alt_m - ned_m.z();
  return g;
}

Eigen::Vector3d enu_from_geodetic(const GeodeticOrigin& origin, const Geodetic& point) {
  return frames::enu_from_ned(ned_from_geodetic(origin, point));
}

Geodetic geodetic_from_enu(const GeodeticOrigin& origin, const Eigen::Vector3d& enu_m) {
  return geodetic_from_ned(origin, frames::ned_from_enu(enu_m));
}

}  // namespace uavsim::common
