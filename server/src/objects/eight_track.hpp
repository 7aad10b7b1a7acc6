// The MBZIRC 2017 truck path (seed 7.1, fig. 7.1a): a figure eight of two circles of radius R whose
// centres are D apart, joined by the two straight lines tangent to both circles that cross midway between
// the centres (internal tangents, D > 2R). Arc-length parametrised; a pure library (no MuJoCo, no clock).
//
// Track frame: origin at the crossing, x from the left circle's centre to the right one's, y to the left.
// s = 0 is the crossing, heading up-right along the first straight; the truck then runs clockwise around
// the right circle, back through the crossing, counter-clockwise around the left circle and home. The
// same convention as vision/eight_track.hpp, so a mission's filter and the server agree on s.
//
// Defaults (90 x 60 m arena centred at the origin): R = 20 m, D = 45 m: an 85 x 40 m eight, 254.5 m long.
#pragma once

#include <string>

#include <Eigen/Core>

namespace uavsim::server::objects {

struct EightTrackParams {
  double circle_radius_m = 20.0;
  double centre_separation_m = 45.0;
  Eigen::Vector2d centre_enu_m = Eigen::Vector2d::Zero();  // the crossing
  double yaw_rad = 0.0;  // the track's x axis from east, counter-clockwise
};

// A point of the track: position, unit direction of travel and signed curvature (1/m, positive left).
struct TrackPoint {
  Eigen::Vector2d position_enu_m = Eigen::Vector2d::Zero();
  Eigen::Vector2d tangent_enu = Eigen::Vector2d::UnitX();
  double curvature_1_m = 0.0;
  double heading_rad() const;  // of the tangent, from east counter-clockwise
};

// Empty if the parameters make an eight, else what is wrong (for startup errors).
std::string validate(const EightTrackParams& params);

// Immutable geometry; every method is const and thread-safe.
class EightTrack {
 public:
  // params must pass validate() (asserted).
  explicit EightTrack(const EightTrackParams& params = {});

  const EightTrackParams& params() const { return params_; }
  double length_m() const { return length_m_; }
  // The point at arc length s (any real s; wrapped into [0, length)).
  TrackPoint at(double s_m) const;
  // Distance from a point to the centre line (closest point over all five pieces).
  double distance_m(const Eigen::Vector2d& p_enu_m) const;

 private:
  Eigen::Vector2d to_enu(const Eigen::Vector2d& p_track) const;

  EightTrackParams params_;
  double c_m_ = 0.0;      // half the centre separation: circle centres at (+-c, 0)
  double phi_rad_ = 0.0;  // the first straight's direction; sin(phi) = R / c
  double a_m_ = 0.0;      // crossing to tangent point: c cos(phi)
  double arc_m_ = 0.0;    // one circle's arc: R (pi + 2 phi)
  double length_m_ = 0.0; // 4a + 2 arc
};

// The MBZIRC 2017 speed schedule (15 km/h for the first 8 minutes, then 5 km/h), from start_s_m at t = 0.
struct SpeedProfile {
  double speed1_m_s = 15.0 / 3.6;
  double speed2_m_s = 5.0 / 3.6;
  double switch_time_s = 480.0;
  double start_s_m = 0.0;
  // Arc length travelled (unwrapped) at sim time t.
  double arc_length_m(double time_s) const;
  double speed_m_s(double time_s) const;
};

}  // namespace uavsim::server::objects
