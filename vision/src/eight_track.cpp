#include "uavsim/vision/eight_track.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "uavsim/common/angles.hpp"

namespace uavsim::vision {

using common::kPi;

namespace {

// Segments in travel order (see the header): 0 crossing -> right tangent point, 1 right circle
// clockwise, 2 straight through the crossing, 3 left circle counter-clockwise, 4 back to the
// crossing.
struct Segment {
  bool arc;
  double s0_m;
  double length_m;
  Eigen::Vector2d start;  // line: start point; arc: circle centre
  Eigen::Vector2d dir;    // line: unit direction
  double theta0_rad;      // arc: start angle about the centre
  double turn;            // arc: +1 counter-clockwise, -1 clockwise
};

double wrap_2pi(double a) {
  a = std::fmod(a, 2.0 * kPi);
  return a < 0.0 ? a + 2.0 * kPi : a;
}

}  // namespace

EightTrack::EightTrack(const EightTrackParams& params) : params_(params) {
  const double r = params_.circle_radius_m;
  half_sep_m_ = 0.5 * params_.centre_separation_m;
  if (!(r > 0.0) || !(half_sep_m_ > r)) {
    throw std::invalid_argument(
        "EightTrackParams: need centre_separation_m > 2 * circle_radius_m > 0 (internal tangents)");
  }
  // internal tangent through the crossing: distance from a centre (c, 0) to the line = c sin(phi) =
  // R
  tangent_angle_rad_ = std::asin(r / half_sep_m_);
  half_straight_m_ = half_sep_m_ * std::cos(tangent_angle_rad_);
  arc_m_ = r * (kPi + 2.0 * tangent_angle_rad_);
  length_m_ = 4.0 * half_straight_m_ + 2.0 * arc_m_;
}

double EightTrack::wrap_s(double s_m) const {
  const double w = std::fmod(s_m, length_m_);
  return w < 0.0 ? w + length_m_ : w;
}

double EightTrack::delta_s(double from_s_m, double to_s_m) const {
  double d = wrap_s(to_s_m - from_s_m);
  if (d >= 0.5 * length_m_) d -= length_m_;
  return d;
}

Eigen::Vector2d EightTrack::track_to_enu(const Eigen::Vector2d& p_track) const {
  return params_.centre_enu_m + Eigen::Rotation2Dd(params_.yaw_rad) * p_track;
}

Eigen::Vector2d EightTrack::enu_to_track(const Eigen::Vector2d& p_enu) const {
  return Eigen::Rotation2Dd(-params_.yaw_rad) * (p_enu - params_.centre_enu_m);
}

// the five segments, built on the fly (cheap) so the class stays a plain value
static void build_segments(double c, double phi, double a, double arc, Segment out[5]) {
  const Eigen::Vector2d u(std::cos(phi), std::sin(phi));   // first straight
  const Eigen::Vector2d w(-std::cos(phi), std::sin(phi));  // second straight
  out[0] = {false, 0.0, a, Eigen::Vector2d::Zero(), u, 0.0, 0.0};
  out[1] = {true, a, arc, Eigen::Vector2d(c, 0.0), Eigen::Vector2d::Zero(), phi + kPi / 2, -1.0};
  out[2] = {false, a + arc, 2.0 * a, a * Eigen::Vector2d(std::cos(phi), -std::sin(phi)),
            w,     0.0,     0.0};
  out[3] = {
      true, 3.0 * a + arc, arc, Eigen::Vector2d(-c, 0.0), Eigen::Vector2d::Zero(), kPi / 2 - phi,
      1.0};
  out[4] = {
      false, 3.0 * a + 2.0 * arc, a, a * Eigen::Vector2d(-std::cos(phi), -std::sin(phi)), u, 0.0,
      0.0};
}

Eigen::Vector2d EightTrack::point_enu(double s_m) const {
  Segment seg[5];
  build_segments(half_sep_m_, tangent_angle_rad_, half_straight_m_, arc_m_, seg);
  const double s = wrap_s(s_m);
  for (int i = 4; i >= 0; --i) {
    if (s < seg[i].s0_m) continue;
    const double local = s - seg[i].s0_m;
    if (!seg[i].arc) return track_to_enu(seg[i].start + local * seg[i].dir);
    const double theta = seg[i].theta0_rad + seg[i].turn * local / params_.circle_radius_m;
    return track_to_enu(seg[i].start + params_.circle_radius_m *
                                           Eigen::Vector2d(std::cos(theta), std::sin(theta)));
  }
  return track_to_enu(Eigen::Vector2d::Zero());
}

Eigen::Vector2d EightTrack::tangent_enu(double s_m) const {
  Segment seg[5];
  build_segments(half_sep_m_, tangent_angle_rad_, half_straight_m_, arc_m_, seg);
  const double s = wrap_s(s_m);
  Eigen::Vector2d t_track = seg[0].dir;
  for (int i = 4; i >= 0; --i) {
    if (s < seg[i].s0_m) continue;
    if (!seg[i].arc) {
      t_track = seg[i].dir;
    } else {
      const double theta =
          seg[i].theta0_rad + seg[i].turn * (s - seg[i].s0_m) / params_.circle_radius_m;
      // d/dtheta of (cos, sin) is (-sin, cos), times the turning direction
      t_track = seg[i].turn * Eigen::Vector2d(-std::sin(theta), std::cos(theta));
    }
    break;
  }
  return Eigen::Rotation2Dd(params_.yaw_rad) * t_track;
}

double EightTrack::curvature_1_m(double s_m) const {
  const double s = wrap_s(s_m);
  const double a = half_straight_m_;
  if (s >= a && s < a + arc_m_) return -1.0 / params_.circle_radius_m;
  if (s >= 3.0 * a + arc_m_ && s < 3.0 * a + 2.0 * arc_m_) return 1.0 / params_.circle_radius_m;
  return 0.0;
}

Eigen::Vector2d EightTrack::point_enu(const TrackCoordinates& c) const {
  const Eigen::Vector2d t = tangent_enu(c.s_m);
  return point_enu(c.s_m) + c.l_m * Eigen::Vector2d(-t.y(), t.x());
}

std::vector<TrackCoordinates> EightTrack::project_all(const Eigen::Vector2d& p_enu_m) const {
  Segment seg[5];
  build_segments(half_sep_m_, tangent_angle_rad_, half_straight_m_, arc_m_, seg);
  const Eigen::Vector2d p = enu_to_track(p_enu_m);
  const double r = params_.circle_radius_m;
  std::vector<std::pair<double, double>> by_distance;  // (distance, s)
  for (const auto& sg : seg) {
    double local = 0.0;
    if (!sg.arc) {
      local = std::clamp((p - sg.start).dot(sg.dir), 0.0, sg.length_m);
    } else {
      const Eigen::Vector2d rel = p - sg.start;
      const double theta = std::atan2(rel.y(), rel.x());
      const double sweep = sg.length_m / r;
      // angle travelled from the arc's start to p's direction, in the arc's turning sense
      const double sigma = wrap_2pi(sg.turn * (theta - sg.theta0_rad));
      if (sigma <= sweep) {
        local = sigma * r;
      } else {
        local = (sigma - sweep < 2.0 * kPi - sigma) ? sg.length_m : 0.0;  // nearer end
      }
    }
    const double s = wrap_s(sg.s0_m + local);
    by_distance.emplace_back((point_enu(s) - p_enu_m).norm(), s);
  }
  std::sort(by_distance.begin(), by_distance.end());
  std::vector<TrackCoordinates> out;
  for (const auto& [d, s] : by_distance) {
    const Eigen::Vector2d t = tangent_enu(s);
    out.push_back({s, (p_enu_m - point_enu(s)).dot(Eigen::Vector2d(-t.y(), t.x()))});
  }
  return out;
}

TrackCoordinates EightTrack::project(const Eigen::Vector2d& p_enu_m, std::optional<double> s_hint_m,
                                     double window_m) const {
  const std::vector<TrackCoordinates> all = project_all(p_enu_m);
  if (s_hint_m) {
    // nearest branch within the window around the hint (all is sorted by distance)
    for (const auto& c : all) {
      if (std::abs(delta_s(*s_hint_m, c.s_m)) <= window_m) return c;
    }
  }
  return all.front();
}

}  // namespace uavsim::vision
