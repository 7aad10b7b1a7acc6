// The field conditions of a run (sim/field_conditions.hpp), from the command line and the world
// file: the realism level (--realism, else the world's <text name="uavsim:realism"
// data="field|ideal"/>, else ideal) with its defaults, then the world's numerics, then --wind:
//   <numeric name="uavsim:wind" data="speed_m_s from_deg [turbulence_sd_m_s] [length_scale_m]
//                                     [gust_rate_hz] [gust_m_s]"/>
//   <numeric name="uavsim:gimbal_dynamics" data="time_const_s [rate_max_deg_s]
//   [accel_max_deg_s2]"/> <numeric name="uavsim:balloon_variation" data="height_spread_m [sway
//   0|1]"/> <numeric name="uavsim:battery_sag" data="internal_resistance_ohm"/>
// Per vehicle, RTK and the sensor errors are parameters (SIM_GPS_RTK, ... in uavsim:params:VEHICLE
// or
// --defaults); per camera, noise, brightness and latency_ms are camera settings (uavsim:camera:CAM,
// --camera).
#pragma once

#include "app/options.hpp"
#include "physics/world.hpp"
#include "sim/field_conditions.hpp"

namespace uavsim::server::app {

// Throws physics::WorldError naming the world attribute that is malformed or out of range.
sim::FieldConditions resolve_field_conditions(const Options& options, const physics::World& world);

}  // namespace uavsim::server::app
