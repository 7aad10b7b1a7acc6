#include "objects/eight_track.hpp"
#include "uavsim/common/angles.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>

#include <Eigen/Geometry>

namespace uavsim::server::objects {

namespace {
using common::kPi;
}  // namespace

double TrackPoint::heading_rad() const { return std::atan2(tangent_enu.y(), tangent_enu.x()); }

std::string validate(const EightTrackParams& p) {
  if (!std::isfinite(p.circle_radius_m) || !(p.circle_radius_m > 0.0)) return "circle radius must be > 0";
  if (!std::isfinite(p.centre_separation_m) || !(p.centre_separation_m > 2.0 * p.circle_radius_m)) {
    return "centre separation must exceed twice the circle radius (the straights must cross)";
  }
  if (!p.centre_enu_m.allFinite() || !std::isfinite(p.yaw_rad)) return "centre and yaw must be finite";
  return "";
}

EightTrack::EightTrack(const EightTrackParams& params) : params_(params) {
  assert(validate(params).empty());
  const double r = params_.circle_radius_m;
  c_m_ = 0.5 * params_.centre_separation_m;
  // the internal tangent through the crossing is at distance c sin(phi) = R from a centre
  phi_rad_ = std::asin(r / c_m_);
  a_m_ = c_m_ * std::cos(phi_rad_);
  arc_m_ = r * (kPi + 2.0 * phi_rad_);
  length_m_ = 4.0 * a_m_ + 2.0 * arc_m_;
}

Eigen::Vector2d EightTrack::to_enu(const Eigen::Vector2d& p_track) const {
  return params_.centre_enu_m + Eigen::Rotation2Dd(params_.yaw_rad) * p_track;
}

TrackPoint EightTrack::at(double s_m) const {
  const double r = params_.circle_radius_m;
  const double cp = std::cos(phi_rad_), sp = std::sin(phi_rad_);
  double s = std::fmod(s_m, length_m_);
  if (s < 0.0) s += length_m_;

  // the five pieces in travel order, in the track frame
  Eigen::Vector2d p, t;
  double k = 0.0;
  auto arc = [&](const Eigen::Vector2d& centre, double theta0, double turn, double local) {
    // turn = -1 clockwise, +1 counter-clockwise; the tangent is turn * d(cos, sin)/dtheta
    const double theta = theta0 + turn * local / r;
    p = centre + r * Eigen::Vector2d(std::cos(theta), std::sin(theta));
    t = turn * Eigen::Vector2d(-std::sin(theta), std::cos(theta));
    k = turn / r;
  };
  if (s < a_m_) {  // crossing -> right tangent point
    t = Eigen::Vector2d(cp, sp);
    p = s * t;
  } else if (s < a_m_ + arc_m_) {  // right circle, clockwise from angle pi/2 + phi
    arc(Eigen::Vector2d(c_m_, 0.0), 0.5 * kPi + phi_rad_, -1.0, s - a_m_);
  } else if (s < 3.0 * a_m_ + arc_m_) {  // the second straight, through the crossing
    t = Eigen::Vector2d(-cp, sp);
    p = a_m_ * Eigen::Vector2d(cp, -sp) + (s - a_m_ - arc_m_) * t;
  } else if (s < 3.0 * a_m_ + 2.0 * arc_m_) {  // left circle, counter-clockwise from pi/2 - phi
    arc(Eigen::Vector2d(-c_m_, 0.0), 0.5 * kPi - phi_rad_, 1.0, s - 3.0 * a_m_ - arc_m_);
  } else {  // back to the crossing
    t = Eigen::Vector2d(cp, sp);
    p = -a_m_ * t + (s - 3.0 * a_m_ - 2.0 * arc_m_) * t;
  }
  TrackPoint out;
  out.position_enu_m = to_enu(p);
  out.tangent_enu = Eigen::Rotation2Dd(params_.yaw_rad) * t;
  out.curvature_1_m = k;
  return out;
}

double EightTrack::distance_m(const Eigen::Vector2d& p_enu_m) const {
  const Eigen::Vector2d q = Eigen::Rotation2Dd(-params_.yaw_rad) * (p_enu_m - params_.centre_enu_m);
  const double r = params_.circle_radius_m;
  const double cp = std::cos(phi_rad_), sp = std::sin(phi_rad_);
  auto segment = [&](const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    const Eigen::Vector2d ab = b - a;
    const double u = std::clamp((q - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
    return (q - (a + u * ab)).norm();
  };
  // an arc covers its circle except the gap facing the crossing; otherwise the nearer end is closest
  auto arc = [&](const Eigen::Vector2d& centre, double inner_angle, const Eigen::Vector2d& end0,
                 const Eigen::Vector2d& end1) {
    const Eigen::Vector2d rel = q - centre;
    double diff = std::remainder(std::atan2(rel.y(), rel.x()) - inner_angle, 2.0 * kPi);
    // the tangent points lie (pi/2 - phi) either side of the direction towards the crossing
    if (std::abs(diff) > 0.5 * kPi - phi_rad_ && rel.norm() > 0.0) return std::abs(rel.norm() - r);
    return std::min((q - end0).norm(), (q - end1).norm());
  };
  const Eigen::Vector2d t1 = a_m_ * Eigen::Vector2d(cp, sp);
  const Eigen::Vector2d t2 = a_m_ * Eigen::Vector2d(cp, -sp);
  double d = std::numeric_limits<double>::infinity();
  d = std::min(d, segment(-t1, t1));
  d = std::min(d, segment(t2, -t2));
  d = std::min(d, arc(Eigen::Vector2d(c_m_, 0.0), kPi, t1, t2));
  d = std::min(d, arc(Eigen::Vector2d(-c_m_, 0.0), 0.0, -t1, -t2));
  return d;
}

double SpeedProfile::arc_length_m(double time_s) const {
  if (time_s <= switch_time_s) return start_s_m + speed1_m_s * time_s;
  return start_s_m + speed1_m_s * switch_time_s + speed2_m_s * (time_s - switch_time_s);
}

double SpeedProfile::speed_m_s(double time_s) const {
  return time_s < switch_time_s ? speed1_m_s : speed2_m_s;
}

}  // namespace uavsim::server::objects
