#include "clearance_envelope.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>

namespace uavsim::missions::mbzirc2017 {

namespace {

// the velocity of the truck's point at r (from the marker's centre): v + omega x r
Eigen::Vector2d point_velocity(const EstimatedTruck& truck, const Eigen::Vector2d& r_enu_m) {
  return truck.velocity_enu_m_s + truck.yaw_rate_rad_s * Eigen::Vector2d(-r_enu_m.y(), r_enu_m.x());
}

}  // namespace

TruckRelative to_truck_frame(const EstimatedTruck& truck, const MissionConfig& config,
                             const Eigen::Vector3d& uav_position_enu_m,
                             const Eigen::Vector3d& uav_velocity_enu_m_s) {
  // r in ENU, turned by -heading; d/dt (R^T r) = R^T (r' - omega x r)
  const Eigen::Rotation2Dd to_truck(-truck.heading_enu_rad);
  const Eigen::Vector2d r = uav_position_enu_m.head<2>() - truck.marker_enu_m;
  const Eigen::Vector2d v = uav_velocity_enu_m_s.head<2>() - point_velocity(truck, r);
  TruckRelative out;
  out.position_m << to_truck * r,
      uav_position_enu_m.z() - config.skid_depth_m - config.deck_height_m;
  out.velocity_m_s << to_truck * v, uav_velocity_enu_m_s.z();
  return out;
}

Eigen::Vector3d enu_velocity_for(const EstimatedTruck& truck,
                                 const Eigen::Vector3d& uav_position_enu_m,
                                 const Eigen::Vector3d& relative_velocity_m_s) {
  const Eigen::Vector2d r = uav_position_enu_m.head<2>() - truck.marker_enu_m;
  const Eigen::Vector2d v = point_velocity(truck, r) + Eigen::Rotation2Dd(truck.heading_enu_rad) *
                                                           relative_velocity_m_s.head<2>();
  return Eigen::Vector3d(v.x(), v.y(), relative_velocity_m_s.z());
}

ClearanceEnvelope::ClearanceEnvelope(const MissionConfig& config) : config_(config) {}

double ClearanceEnvelope::floor_height_m() const {
  return config_.cab_top_above_deck_m + config_.cab_vertical_margin_m;
}

double ClearanceEnvelope::box_front_m() const {
  // the skids on the deck, and the propellers' tips short of the cab's rear face
  return std::min(config_.deck_front_m - config_.skid_reach_m,
                  config_.cab_rear_m - config_.rotor_reach_m) -
         config_.clearance_margin_m;
}

double ClearanceEnvelope::box_rear_m() const {
  return -(config_.deck_rear_m - config_.skid_reach_m - config_.clearance_margin_m);
}

double ClearanceEnvelope::box_half_width_m() const {
  return config_.deck_half_width_m - config_.skid_reach_m - config_.clearance_margin_m;
}

bool ClearanceEnvelope::in_box(const Eigen::Vector2d& p_m) const {
  return p_m.x() >= box_rear_m() && p_m.x() <= box_front_m() &&
         std::abs(p_m.y()) <= box_half_width_m();
}

EnvelopeCheck ClearanceEnvelope::check(const TruckRelative& r) const {
  EnvelopeCheck c;
  const Eigen::Vector2d p = r.position_m.head<2>();
  const Eigen::Vector2d v = r.velocity_m_s.head<2>();
  c.above_floor = r.position_m.z() >= floor_height_m();
  c.in_deck_box = in_box(p) && in_box(p + v * config_.envelope_prediction_s);
  c.matched = v.norm() <= config_.matched_speed_m_s;
  c.centred = p.norm() <= config_.centred_m && v.norm() <= config_.open_loop_matched_m_s;
  return c;
}

double ClearanceEnvelope::limit_vertical_m_s(const TruckRelative& r, double vz_m_s) const {
  if (check(r).cleared_below_floor()) return vz_m_s;
  // towards the floor and no further: descend at most gain * gap (a climb below it)
  return std::max(vz_m_s, config_.floor_approach_gain_1_s * (floor_height_m() - r.position_m.z()));
}

namespace {

// The cab's volume in (x, y, skid height) as the UAV must see it: the box widened by the
// propellers' reach and the margin; vertically, the UAV (skids to propellers' top) overlaps the cab
// when its skids are below the cab's top (plus the margin) and its propellers above the cab's
// bottom. Separations from the six faces, positive outside: rear, front, left, right, top, bottom.
std::array<double, 6> cab_separations(const MissionConfig& c, const Eigen::Vector3d& p) {
  const double reach = c.rotor_reach_m + c.clearance_margin_m;
  const double half_width = c.cab_half_width_m + reach;
  return {(c.cab_rear_m - reach) - p.x(),
          p.x() - (c.cab_front_m + reach),
          p.y() - half_width,
          -half_width - p.y(),
          p.z() - (c.cab_top_above_deck_m + c.cab_vertical_margin_m),
          (c.cab_bottom_above_deck_m - c.prop_top_above_skids_m) - p.z()};
}

}  // namespace

bool ClearanceEnvelope::in_cab_volume(const Eigen::Vector3d& p_m) const {
  const std::array<double, 6> s = cab_separations(config_, p_m);
  return *std::max_element(s.begin(), s.end()) < 0.0;
}

Eigen::Vector3d ClearanceEnvelope::abort_velocity_m_s(const Eigen::Vector3d& p_m) const {
  // the face with the largest separation among those a climb does not cross (all but the bottom):
  // outside it, a ray with a non-negative component along its outward normal stays outside, and the
  // climb is such a component for the top face and orthogonal to the four sides
  const std::array<double, 6> s = cab_separations(config_, p_m);
  const size_t face = static_cast<size_t>(std::max_element(s.begin(), s.begin() + 5) - s.begin());
  static const std::array<Eigen::Vector2d, 5> kNormal = {
      Eigen::Vector2d(-1, 0), Eigen::Vector2d(1, 0), Eigen::Vector2d(0, 1), Eigen::Vector2d(0, -1),
      Eigen::Vector2d(0, 0)};
  const Eigen::Vector2d retreat = kNormal[face] * config_.abort_retreat_m_s;
  return Eigen::Vector3d(retreat.x(), retreat.y(), config_.abort_climb_m_s);
}

}  // namespace uavsim::missions::mbzirc2017
