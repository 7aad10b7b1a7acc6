// The safety shell around the funnel of seed fig. 7.7: a landing that cannot fly into the truck.
// From the UAV's own estimate of the truck (the marker track: its centre, velocity, heading and
// yaw rate) and the deck's geometry the team measured before the competition (MissionConfig), in
// the truck's frame:
//   - the floor: skids at the cab's top plus a margin. Above it no part of the UAV can touch the
//     cab, and the funnel decides alone;
//   - below it, only inside the deck box (skids on the deck, propellers short of the cab's rear
//     face, now and envelope_prediction_s ahead) with the velocity matched to the deck's;
//   - the open-loop last metres (the marker too close to see) only from centred and matched;
//   - otherwise a climb-away: the truck's own velocity (so the UAV goes along the truck's heading)
//     plus a climb and a retreat along the outward normal of a face of the cab's volume that
//     separates the UAV from it. Relative to the truck that path is a ray which stays in that
//     face's outer half-space, so it never crosses the cab's volume. (Under the cab's bottom, in
//     the chassis, there is no such face; the deck box keeps the UAV from ever being there.)
// Pure: no I/O, no clock.
#pragma once

#include <Eigen/Core>

#include "mission_config.hpp"

namespace uavsim::missions::mbzirc2017 {

// The truck as the UAV's estimate has it.
struct EstimatedTruck {
  Eigen::Vector2d marker_enu_m =
      Eigen::Vector2d::Zero();  // the marker's centre, extrapolated to now
  Eigen::Vector2d velocity_enu_m_s = Eigen::Vector2d::Zero();
  double heading_enu_rad = 0.0;  // the truck's x axis (forward) from east, counter-clockwise
  double yaw_rate_rad_s = 0.0;   // positive turning left
};

// The UAV in the truck's frame: x forward, y left, from the marker's centre; z is the skids' height
// above the deck top. The velocity is relative to the truck's frame (its turning included): what
// the UAV's position in that frame changes by per second.
struct TruckRelative {
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d velocity_m_s = Eigen::Vector3d::Zero();
};

// (truck estimate, UAV body origin and velocity in ENU) => the UAV in the truck's frame.
TruckRelative to_truck_frame(const EstimatedTruck& truck, const MissionConfig& config,
                             const Eigen::Vector3d& uav_position_enu_m,
                             const Eigen::Vector3d& uav_velocity_enu_m_s);

// (truck estimate, UAV position, a velocity relative to the truck's frame) => the ENU velocity
// command that gives it: the velocity of the truck's point under the UAV plus the relative one
// turned into ENU. Inverse of to_truck_frame's velocity.
Eigen::Vector3d enu_velocity_for(const EstimatedTruck& truck,
                                 const Eigen::Vector3d& uav_position_enu_m,
                                 const Eigen::Vector3d& relative_velocity_m_s);

// What the envelope says about one relative state.
struct EnvelopeCheck {
  bool above_floor = false;  // skids above the cab's top plus the vertical margin
  bool in_deck_box = false;  // in the deck box now and envelope_prediction_s ahead
  bool matched = false;      // relative horizontal speed at most matched_speed_m_s
  bool centred = false;      // within centred_m of the centre, at most open_loop_matched_m_s
  // below the floor is allowed
  bool cleared_below_floor() const { return in_deck_box && matched; }
  // the state is inside the envelope (above the floor, or cleared below it)
  bool safe() const { return above_floor || cleared_below_floor(); }
  // the open-loop last metres may begin
  bool ready_for_open_loop() const { return in_deck_box && matched && centred; }
};

// Immutable; thread-safe.
class ClearanceEnvelope {
 public:
  explicit ClearanceEnvelope(const MissionConfig& config);

  // The skids' height above the deck below which the deck box rule holds.
  double floor_height_m() const;
  // The deck box for the UAV's centre: x in [rear, front], |y| <= half width (truck frame).
  double box_front_m() const;
  double box_rear_m() const;
  double box_half_width_m() const;
  // Whether a centre at (x, y) in the truck frame is inside the deck box.
  bool in_box(const Eigen::Vector2d& p_m) const;

  EnvelopeCheck check(const TruckRelative& r) const;

  // A descent rate (vz_m_s, negative down) limited so that the UAV does not go below the floor
  // unless cleared there: it approaches the floor at floor_approach_gain_1_s and holds; below it,
  // uncleared, it climbs back.
  double limit_vertical_m_s(const TruckRelative& r, double vz_m_s) const;

  // Whether a UAV at p (truck frame) has any part in the cab's volume widened by the propellers'
  // reach and the margins (the volume the abort path must not cross).
  bool in_cab_volume(const Eigen::Vector3d& p_m) const;
  // The climb-away's velocity relative to the truck's frame from p: the climb plus a retreat along
  // the outward normal of the cab volume's face with the largest separation (none for its top).
  Eigen::Vector3d abort_velocity_m_s(const Eigen::Vector3d& p_m) const;

 private:
  MissionConfig config_;
};

}  // namespace uavsim::missions::mbzirc2017
