// Parameters of the coverage flock (the thesis the project descends from, chapters 3 and 4): the
// area, the sensor footprint, the flocking gains of table 4.1 and the timing of the overlay
// network. Plain values with the thesis's numbers as defaults; validate() range-checks a whole
// configuration before any of it reaches a loop, a division or an allocation.
#pragma once

#include <string>

#include "uavsim/common/angles.hpp"

namespace uavsim::missions::coverage {

// Algorithm 3's constants, table 4.1 (distances in m, speeds in m/s, R2 in deg/s).
struct FlockGains {
  double d_r1_m = 7.5;        // D_R1: separation threshold (25% under Y_sensor, footnote 6)
  double c_p_r1 = 0.5;        // c_p_R1: multiplier of the squared parallel distance
  double c_o_r1 = 0.6;        // c_o_R1: multiplier of the orthogonal term
  double d_r1 = 0.4;          // d_R1: exponent of the orthogonal term
  double s_r1_m_s = 0.8;      // s_R1: saturation of R1
  double kp_r2 = 5.0;         // k_p_R2: alignment gain (1/s)
  double s_r2_deg_s = 180.0;  // s_R2: saturation of the yaw rate
  double kp_r3x = 0.2;        // k_p_R3x
  double ki_r3x = 0.0005;     // k_I_R3x
  double s_r3x_m_s = 2.0;     // s_R3x
  double kp_r3y = 0.1;        // k_p_R3y
  double s_r3y_m_s = 2.0;     // s_R3y
  // Beyond Algorithm 3: where R1 pushes us towards the leader (our nearest neighbour is on our far
  // side), we also close on the next agent towards the leader, at kp_close_gap * (its distance
  // across - D_R1) capped by R3y and by s_close_gap_m_s, and the faster of that and R1 applies.
  // Algorithm 3 applies R1 alone, which near D_R1 is a crawl (0.6 * (1 - (7.4 / 7.5)^0.4) = 3
  // mm/s): a tail of agents settled under D_R1 from each other stayed 10-11 m from the rest for
  // tens of seconds after a deploy, more than a footprint (25 quads over 600 x 600 m).
  // Proportional, so that we stop at D_R1 instead of running into it (at R3y's full speed the line
  // compressed to 5.7-6 m, a narrower swath). Only while the leader flies no faster than
  // close_gap_leader_speed_m_s: closing at 2 m/s on top of a deploy's 8 m/s, two followers were
  // still 2.5 m/s apart when the leader braked at the deploy's end and collided, twice (25 quads,
  // --gcs, p = 0.003, seed 2, 14 crashed). false: Algorithm 3 as written.
  bool close_gap = true;
  double kp_close_gap = 0.5;                // 1/s
  double s_close_gap_m_s = 1.0;             // m/s
  double close_gap_leader_speed_m_s = 6.0;  // m/s: over the 5 m/s cruise, under the 8 m/s deploy
};

struct CoverageConfig {
  // the rectangle, in the world's ENU frame: x in [origin_x, origin_x + length_x], y likewise. The
  // flock flies along x (the thesis's H axis) and its line lies along y.
  double origin_x_m = 0.0;
  double origin_y_m = 0.0;
  double length_x_m = 600.0;
  double width_y_m = 600.0;

  // sensor footprint at altitude_m (section 4.3: 7 m x 10 m); the footprint is axis aligned when
  // the heading is within heading_tolerance_rad of +x or -x
  double x_sensor_m = 7.0;
  double y_sensor_m = 10.0;
  double altitude_m = 20.0;
  double altitude_tolerance_m = 1.0;
  double heading_tolerance_rad = 0.1;
  // stripe height = length_x / ceil(length_x / (stripe_fill * x_sensor)): a picture covers a whole
  // stripe when its centre is within (x_sensor - stripe height) / 2 of the stripe's centre
  double stripe_fill = 0.8;

  FlockGains gains;

  // overlay network (3.3): broadcasts per second, and the age a record may reach before eviction,
  // allowed_age(d) = base + per_hop * d (Algorithm 2's MAX_ALLOWED_AGE)
  double broadcast_hz = 8.0;
  double max_age_base_s = 1.5;
  double max_age_per_hop_s = 1.0;

  // aggregation query (3.4): retransmission period of an unacknowledged partial result
  double query_retransmit_s = 0.5;

  // path planning (3.5): speed along a planned path, the margin that overlaps the flock's edge
  // with the frontier (fraction of y_sensor), the lateral step that thresholds a control point
  // out, and the half-width of the moving-average smoothing (control points)
  double cruise_speed_m_s = 5.0;
  // Deploying (fig. 4.6): the leader's speed to the start of its next path. A transit, outside the
  // rectangle (the flock's pictures are all taken at cruise_speed_m_s), usually one swath sideways:
  // ~170 m for 25 agents, 34 s at the cruise speed
  double deploy_speed_m_s = 8.0;
  double edge_margin_fraction = 0.2;
  double lateral_threshold_m = 30.0;
  int smoothing_half_window = 2;
  // the flock is formed / has caught up when every member is within this of its line position
  double formation_tolerance_m = 3.0;
  // a leader that reaches the start of a path waits at most this long for the flock
  double deploy_timeout_s = 60.0;

  // going home (fig. 4.6): each agent returns at altitude_m + (id % home_layers) * home_layer_m so
  // that crossing tracks are separated vertically, at home_speed_m_s (no pictures are taken on the
  // way home, so nothing ties it to the cruise speed; the autopilot's WPNAV_SPEED caps it at 12
  // m/s), then lands at its take-off point
  int home_layers = 4;
  double home_layer_m = 3.0;
  double home_speed_m_s = 12.0;
  // a follower's commanded speed is capped here (above deploy_speed_m_s, so it can catch up; the
  // autopilot's own cap is 1.2 x WPNAV_SPEED, 12 m/s)
  double max_speed_m_s = 11.0;

  // Empty when usable, else what is wrong (names the field).
  std::string validate() const;
  int stripe_count() const;
  double stripe_height_m() const;
};

using common::kPi;

// Agent ids are 0..kMaxAgents-1 (the radio messages carry id sets as 64-bit masks).
inline constexpr int kMaxAgents = 64;

}  // namespace uavsim::missions::coverage
