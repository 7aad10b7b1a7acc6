// What a mission's state machine asks of its vehicle at a step, carried out by the vehicle program
// (uavsim::mission::fly, program.hpp). The MBZIRC 2017 landing FSM's and the MBZIRC 2020 UAV FSM's
// outputs begin with it.
#pragma once

#include <Eigen/Core>

namespace uavsim::mission {

struct FlightCommand {
  enum class Action {
    kNone,
    kArmAndTakeOff,  // GUIDED, armed, climbing to takeoff_altitude_m
    kVelocity,       // the velocity setpoint velocity_enu_m_s
    kForceDisarm,    // all motors off at once, in flight if need be
  };
  Action action = Action::kNone;
  Eigen::Vector3d velocity_enu_m_s = Eigen::Vector3d::Zero();  // kVelocity
  double takeoff_altitude_m = 0.0;                             // kArmAndTakeOff
};

}  // namespace uavsim::mission
