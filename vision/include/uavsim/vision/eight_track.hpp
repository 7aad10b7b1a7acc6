// The MBZIRC 2017 truck track (seed 7.1, fig. 7.1a, 7.5): a figure eight made of two circles of
// radius R whose centres are D apart, joined by the two straight lines tangent to both circles that
// cross midway between the centres (internal tangents; they exist when D > 2R). Arc-length
// parametrised.
//
// Track frame: origin at the crossing, x from the left circle's centre to the right one's, y to the
// left of x. The world pose is a centre position in ENU and a yaw of the track's x axis from east.
// s = 0 is the crossing, travelling up-right (+x, +y) along the first straight; the eight is then
// run clockwise around the right circle and counter-clockwise around the left one. The lateral
// offset l is positive to the left of the direction of travel.
//
// Defaults (MBZIRC 2017 arena 90 x 60 m, centred at the ENU origin, x along east): R = 20 m, D = 45
// m give an 85 x 40 m eight, 2.5 m from the short sides of the arena; total length 254.5 m, one lap
// per 61 s at 15 km/h. The server's truck path uses the same EightTrackParams.
#pragma once

#include <Eigen/Core>
#include <optional>
#include <vector>

namespace uavsim::vision {

struct EightTrackParams {
  double circle_radius_m = 20.0;
  double centre_separation_m = 45.0;
  Eigen::Vector2d centre_enu_m = Eigen::Vector2d::Zero();
  double yaw_rad = 0.0;  // the track's x axis from east, counter-clockwise
};

// The track's position and lateral offset of a point.
struct TrackCoordinates {
  double s_m = 0.0;  // arc length in [0, length)
  double l_m = 0.0;  // lateral offset, positive left of the direction of travel
};

// Immutable track geometry. All methods are const and thread-safe.
class EightTrack {
 public:
  // Throws std::invalid_argument unless centre_separation_m > 2 * circle_radius_m > 0 (a config
  // error).
  explicit EightTrack(const EightTrackParams& params = {});

  const EightTrackParams& params() const { return params_; }
  double length_m() const { return length_m_; }

  // s wrapped into [0, length).
  double wrap_s(double s_m) const;
  // The shortest signed arc length from a to b, in [-length/2, length/2).
  double delta_s(double from_s_m, double to_s_m) const;

  // Point on the centre line at arc length s (wrapped), in ENU (x, y).
  Eigen::Vector2d point_enu(double s_m) const;
  // Unit direction of travel at s.
  Eigen::Vector2d tangent_enu(double s_m) const;
  // Signed curvature at s (1/m, positive turning left): -1/R on the right circle, +1/R on the left,
  // 0 on the straights.
  double curvature_1_m(double s_m) const;
  // point(s) + l * left normal(s).
  Eigen::Vector2d point_enu(const TrackCoordinates& c) const;

  // Projects a world point onto the track: the closest centre-line point's s and the signed offset.
  // Near the crossing two branches are close; s_hint (with window_m) picks the branch near an
  // expected arc length, as the Kalman filter's prediction does. Falls back to the global nearest
  // when no branch lies within the window.
  TrackCoordinates project(const Eigen::Vector2d& p_enu_m, std::optional<double> s_hint_m = {},
                           double window_m = 15.0) const;

  // The closest point of every branch (one per straight or arc), nearest first: near the crossing
  // the first two are both plausible, and only the direction of motion tells them apart.
  std::vector<TrackCoordinates> project_all(const Eigen::Vector2d& p_enu_m) const;

 private:
  Eigen::Vector2d track_to_enu(const Eigen::Vector2d& p_track) const;
  Eigen::Vector2d enu_to_track(const Eigen::Vector2d& p_enu) const;

  EightTrackParams params_;
  double half_sep_m_ = 0.0;         // c: circle centres at (+-c, 0)
  double tangent_angle_rad_ = 0.0;  // phi: the first straight's direction, sin(phi) = R / c
  double half_straight_m_ = 0.0;    // a = c cos(phi): crossing to tangent point
  double arc_m_ = 0.0;              // R (pi + 2 phi)
  double length_m_ = 0.0;           // 4a + 2 R (pi + 2 phi)
};

}  // namespace uavsim::vision
