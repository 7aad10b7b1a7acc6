// The rules every mode shares: entering a mode (the common resets), the idle on the ground,
// auto-disarm and the pilot's throttle take-off. The modes themselves, one object each, are in
// flight_modes.cpp; the services they fly with (the carrot, take-off, the land descent, the sticks)
// in mode_context.cpp.
#include <optional>
#include <string>

#include "fc/fc_impl.hpp"
#include "fc/flight_controller.hpp"

namespace uavsim::server::fc {

bool FlightController::Impl::gps_mode(Mode mode) const { return modes_.of(mode).needs_position(); }

bool FlightController::Impl::enter_mode(Mode mode, bool from_failsafe) {
  // position modes need a position estimate
  if (gps_mode(mode) && !(estimator_.state().gps_ok && estimator_converged_)) {
    status(4, std::string("Mode change to ") + mode_name(mode) + " failed: requires position");
    return false;
  }
  if (mode == Mode::kAuto && mission_.items.size() < 2) {
    status(4, "Mode change to AUTO failed: no mission");
    return false;
  }
  {
    ModeContext ctx = mode_context();
    modes_.of(mode_).exit(ctx);
  }
  mode_ = mode;
  if (!from_failsafe) status(6, std::string("Mode ") + mode_name(mode));
  // a commanded heading, speed changes and a take-off in progress belong to the old mode
  yaw_.fixed = false;
  yaw_.rate_mode = false;
  yaw_.slew_override_rad_s = 0.0;
  nav_.speed_xy_override_m_s = 0.0;
  nav_.speed_up_override_m_s = 0.0;
  nav_.speed_dn_override_m_s = 0.0;
  if (flight_.armed) init_mode_state();
  return true;
}

void FlightController::Impl::init_mode_state() {
  const bool flying = flight_.armed && !flight_.landed;
  // a GUIDED take-off ends with any change to another mode (LAND during the climb must be able to
  // detect its landing); AUTO's take-off items start their own
  if (mode_ != Mode::kGuided) flight_.takeoff_active = false;
  nav_.active = false;
  command_.attitude_climb = false;
  guided_.sub = GuidedSub::kHold;
  pilot_.flying_xy = false;
  ModeContext ctx = mode_context();
  nav_.hold_position_enu_m = ctx.stopping_point();
  active_mode().enter(ctx, flying);
}

void FlightController::Impl::start_mission_item(int seq) {
  ModeContext ctx = mode_context();
  modes_.automatic.start_item(ctx, seq);
}

void FlightController::Impl::run_mode(double dt_s) {
  const ParamValues& p = params_.values();
  FlightMode& mode = active_mode();
  // the pilot's yaw stick turns the vehicle at a rate in the modes that read the sticks
  const std::optional<PilotInput> in = pilot();
  if (mode.reads_pilot()) {
    yaw_.rate_mode = in.has_value();
    yaw_.rate_cmd_rad_s =
        in ? -in->yaw * params_.derived().rate_y_max_rad_s : 0.0;  // stick right: clockwise
  }
  // on the ground and not taking off: idle, and auto-disarm after DISARM_DELAY (unless the pilot's
  // throttle takes off)
  if (flight_.landed && !flight_.takeoff_active && !pilot_takeoff()) {
    command_.kind = ControlKind::kIdle;
    nav_.active = false;
    if (mode.disarms_when_landed()) {
      do_disarm("Disarming motors: landed");
      return;
    }
    if (p.disarm_delay > 0.0 && now() - landed_since_s_ >= p.disarm_delay) {
      do_disarm("Auto disarm: landed");
    }
    return;
  }
  ModeContext ctx = mode_context();
  mode.update(ctx, dt_s);
}

// ---------------------------------------------------------------------------------------------------
// the pilot's throttle takes off from the ground in STABILIZE, ALT_HOLD and LOITER, as in
// ArduCopter

bool FlightController::Impl::pilot_takeoff() {
  const std::optional<PilotInput> in = pilot();
  if (!flight_.armed || !in || in->throttle <= 0.5 + kThrottleDeadzone) return false;
  if (mode_ == Mode::kLoiter && !estimator_.position_ok()) return false;
  flight_.landed = false;
  restart_for_takeoff();
  nav_.hold_position_enu_m = estimator_.state().position_enu_m;
  command_.setpoint.position_enu_m = nav_.hold_position_enu_m;
  command_.setpoint.velocity_enu_m_s.setZero();
  pilot_.flying_xy = false;
  status(6, "Takeoff");
  return true;
}

}  // namespace uavsim::server::fc
