// The MBZIRC 2017 landing mission's numbers (seed 7.1), in one place: what the team knew before the
// competition (arena, the eight's shape, the marker and the deck height) and the mission's own
// tuning.
#pragma once

#include <Eigen/Core>

#include "uavsim/vision/eight_track.hpp"

namespace uavsim::missions::mbzirc2017 {

struct MissionConfig {
  // the arena and the truck (competition rules): the eight's centre is the arena's centre
  Eigen::Vector2d arena_centre_enu_m = Eigen::Vector2d::Zero();
  vision::EightTrackParams track;  // R 20 m, centres 45 m apart
  double deck_height_m = 1.5;      // the marker's plane above the ground

  // the hexa: skid bottoms below the body origin (telemetry's position), and the camera under it
  double skid_depth_m = 0.362;
  Eigen::Vector3d camera_offset_body_m = Eigen::Vector3d(0.0, 0.0, -0.09);

  // Go To Centre / Intercept / Wait Until Visible (fig. 7.6)
  double cruise_altitude_m = 8.0;  // seed 7.1: the centre at 8 m
  double cruise_speed_m_s = 7.0;   // the UAV's speed profile for interception
  double altitude_gain_1_s = 1.0;  // vertical P on altitude while cruising
  double max_climb_m_s = 2.0;
  double arrive_radius_m = 2.0;    // "on the interception point"
  double arrive_time_s = 1.0;      // or about to meet the truck
  double search_timeout_s = 12.0;  // Wait Until Visible: seed 7.1
  double seen_recently_s = 0.5;    // a detection this fresh counts as "seen"

  // Approach: PID on the marker offset plus the truck's velocity (feed-forward from the filter)
  double approach_kp_1_s = 1.0;
  double approach_ki_1_s2 = 0.3;
  double approach_kd = 0.0;  // the PID's derivative acts on the UAV's own position: on a moving
                             // target it would brake
  double approach_max_speed_m_s = 9.0;
  double lost_after_s = 1.0;           // no detection for this long: the marker is lost
  double lost_give_up_s = 8.0;         // lost above the open-loop height this long: Go To Centre
  double climb_m_s = 0.8;              // outside the funnel, or lost: climb for safety
  double open_loop_height_m = 1.6;     // skids above the deck below which the marker no longer fits
                                       // (in the sweeps its last sightings were at 1.4-1.5 m)
  double open_loop_timeout_s = 8.0;    // seed 7.1: up to 8 s of open-loop descent
  double open_loop_descent_m_s = 0.6;  // short: the filter extrapolates blind meanwhile

  // the funnel-shaped safe volume (fig. 7.7), see funnel.hpp
  double funnel_base_radius_m =
      0.4;                     // at the deck: skids within the 2.2 m deck, props clear of the cab
  double funnel_slope = 0.45;  // radius growth per metre of height
  double funnel_max_radius_m = 3.5;
  // descent rate inside the funnel: slow near the deck (touchdown at ~0.4 m/s, well under the
  // 1 m/s landing limit), faster high up
  double descent_min_m_s = 0.4;
  double descent_max_m_s = 1.2;
  double descent_per_m_1_s = 0.15;

  // the truck as the team measured it before the competition (models/objects/truck.xml), from the
  // marker's centre on the deck, x forward: the deck's edges and the cab's box
  double deck_front_m = 1.1;
  double deck_rear_m = 1.1;
  double deck_half_width_m = 1.1;
  double cab_rear_m = 2.0;  // the cab's rear face
  double cab_front_m = 3.0;
  double cab_half_width_m = 1.0;
  double cab_top_above_deck_m = 0.55;
  double cab_bottom_above_deck_m = -0.15;
  // the hexa's reach from its centre (models/vehicles/hexa.xml): propeller tips at 0.45 + 0.19 m,
  // skid corners at 0.212 * sqrt(2) m at any yaw; and its propellers' top above its skids' bottom
  double rotor_reach_m = 0.64;
  double skid_reach_m = 0.30;
  double prop_top_above_skids_m = 0.44;

  // the clearance envelope around the funnel (clearance_envelope.hpp)
  double clearance_margin_m = 0.1;      // horizontal, on the deck box and the cab's box
  double cab_vertical_margin_m = 0.25;  // the floor: skids this far above the cab's top
  double matched_speed_m_s = 0.5;       // horizontal speed relative to the deck: "matched"
  double envelope_prediction_s = 0.5;   // in the deck box now and this far ahead
  double centred_m = 0.45;              // the open-loop last metres only this close to the centre
  double open_loop_matched_m_s = 0.5;   // and this slow relative to the deck
  // a sighting older than this is stale: no descent on it above the open-loop height (the marker
  // gone from there is lost, not too close), and the open-loop readiness is taken on fresh ones
  // only (2 frames at 7 frames/s and the processing latency)
  double fresh_sighting_s = 0.4;
  // the blind descent aims this far behind the marker's centre, away from the cab: the truck's
  // extrapolation drifts when blind (0.5 m/s seen in a curve at 18 km/h)
  double open_loop_aim_back_m = 0.25;
  // the blind last metres are committed to from here only when centred and matched: above it the
  // UAV holds until they are
  double commit_height_m = 2.0;
  // the skids' height above the deck at which the marker leaves the image (the 1.5 m marker fills
  // the down camera's 65 deg field of view; ground truth of the sweeps: the blind last metres began
  // 1.0-1.1 m above the deck): with the barometric change since, the height in the blind last
  // metres whatever the barometer's drift
  double marker_lost_height_m = 1.05;
  // the FC's position estimate stepping in the blind last metres (estimate_monitor.hpp): at or
  // below this the motors go off, the deck nearer than any way out; above it the UAV climbs over
  // the cab
  double drop_height_m = 0.45;
  // blind, this far below the deck's top by the blind height without a touchdown: the deck is not
  // under the skids (the propellers, 0.44 m above them, reach the deck's underside at about 0.5 m)
  double deck_missed_m = 0.15;
  // blind, the correction towards the aim point is at most this fast relative to the truck: half
  // the matched speed, so the relative motion stays within what the readiness checked
  double open_loop_correction_m_s = 0.25;
  double abort_climb_m_s = 1.5;          // the climb-away
  double abort_retreat_m_s = 1.0;        // away from the cab, relative to the truck
  double abort_clear_height_m = 2.5;     // skids above the deck where a climb-away ends
  double floor_approach_gain_1_s = 1.0;  // descent towards the floor when not cleared below it

  // vision (seed 7.1: ~7 frames/s on the TX1)
  double vision_latency_s = 0.1;  // processing time of one frame (detached timing)
};

}  // namespace uavsim::missions::mbzirc2017
