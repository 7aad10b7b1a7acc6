// The coverage flock's world (the thesis the project descends from, section 4.3): N quads on a
// take-off line along y, just outside the x = origin edge of the W x H rectangle they cover, on a
// ground plane that holds the rectangle and the line. The quads are models/vehicles/quad.xml with
// its 3S battery (thesis eqs. 4.6-4.9: 5000 mAh, 5 W of boards, the template's
// `uavsim:quad:battery`); the composer expands the <uavsim_vehicle> elements. Pure: returns MJCF
// text.
#pragma once

#include <string>

namespace uavsim::missions::coverage {

struct WorldSpec {
  int agents = 5;
  double length_x_m = 150.0;  // W: the flight direction
  double width_y_m = 100.0;   // H: across it
  double origin_x_m = 0.0;
  double origin_y_m = 0.0;
  double line_offset_m = 10.0;  // the take-off line lies this far before the x = origin edge
  // between neighbours on the line: a little under the flocking separation D_R1 (7.5 m), so the
  // flock takes off already in formation (formed, it settles ~6.7 m apart). From 10 m apart, 25
  // quads took 40 s to close up, the first pass spread wider than the rest, and its ramp left the
  // next passes notches and holes.
  double line_spacing_m = 7.0;
  // the autopilots' LAND descent (ArduCopter LAND_SPEED below 10 m, LAND_SPEED_HIGH above): the
  // flock lands from 20-29 m at the end of the mission, which at ArduCopter's defaults (0.5 and
  // 1.5 m/s) takes 27-33 s; 1 m/s at touchdown is a third of the simulator's hard-impact speed
  double land_speed_m_s = 1.0;
  double land_speed_high_m_s = 3.0;

  // Empty when usable, else what is wrong (names the field).
  std::string validate() const;
};

// The take-off point of agent i (world ENU, on the ground).
void takeoff_point(const WorldSpec& spec, int i, double* x_m, double* y_m);

// The world as MJCF with uavsim elements (spec must validate()).
std::string coverage_world_xml(const WorldSpec& spec);

}  // namespace uavsim::missions::coverage
