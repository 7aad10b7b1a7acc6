#include "fc/flight_controller.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "fc/angles.hpp"
#include "fc/fc_impl.hpp"

namespace uavsim::server::fc {

namespace {

// control steps longer than this (a paused sim) are treated as this long
constexpr double kMaxDtS = 0.05;
// GUIDED velocity sanity limit, as ArduCopter's SET_POSITION_TARGET handler
constexpr double kMaxGuidedSpeedM_S = 1000.0;
// below this fraction of hover thrust the rate integrators bleed off with time constant kRelaxTauS
constexpr double kRelaxThrustFraction = 0.5;
constexpr double kRelaxTauS = 0.2;
// the motor monitor judges only well clear of the ground (contact torques are not the model's) and
// with a collective near hover (no spin-up or free-fall transients)
constexpr double kMonitorMinHeightM = 1.0;
constexpr double kMonitorMinThrustFraction = 0.5;


bool finite(const Eigen::Vector3d& v) { return v.allFinite(); }

bool finite(const TruthState& t) {
  return t.position_enu_m.allFinite() && t.velocity_enu_m_s.allFinite() &&
         t.q_enu_body.coeffs().allFinite() && t.rate_body_rad_s.allFinite() &&
         t.accel_enu_m_s2.allFinite() && t.q_enu_body.norm() > 0.5;
}

}  // namespace

const char* mode_name(Mode mode) {
  switch (mode) {
    case Mode::kStabilize: return "STABILIZE";
    case Mode::kAltHold: return "ALT_HOLD";
    case Mode::kAuto: return "AUTO";
    case Mode::kGuided: return "GUIDED";
    case Mode::kLoiter: return "LOITER";
    case Mode::kRtl: return "RTL";
    case Mode::kLand: return "LAND";
    case Mode::kBrake: return "BRAKE";
  }
  return "UNKNOWN";
}

std::optional<Mode> mode_from_number(uint32_t custom_mode) {
  switch (custom_mode) {
    case 0: return Mode::kStabilize;
    case 2: return Mode::kAltHold;
    case 3: return Mode::kAuto;
    case 4: return Mode::kGuided;
    case 5: return Mode::kLoiter;
    case 6: return Mode::kRtl;
    case 9: return Mode::kLand;
    case 17: return Mode::kBrake;
    default: return std::nullopt;
  }
}

// ---------------------------------------------------------------------------------------------------
// Impl: construction and the control step

FlightController::Impl::Impl(const airframe::AirframeParams& airframe, uint64_t seed)
    : airframe_(airframe),
      mass_kg_(airframe.mass_kg),
      inertia_(airframe.inertia_body_kgm2),
      params_(airframe.battery.capacity_mah),
      mixer_(airframe),
      motor_monitor_(airframe),
      sensors_(seed) {
  if (!(mass_kg_ > 0.0)) mass_kg_ = 1.0;
  if (airframe.rotors.size() >= MotorMonitor::kMinRotors) {
    degraded_mixers_.reserve(airframe.rotors.size());
    for (std::size_t k = 0; k < airframe.rotors.size(); ++k) {
      try {
        degraded_mixers_.emplace_back(Mixer(airframe, k));
      } catch (const std::invalid_argument&) {
        degraded_mixers_.emplace_back(std::nullopt);  // this loss cannot be flown: keep the full mixer
      }
    }
  }
  hover_thrust_n_ = mass_kg_ * kGravityM_S2;
  mission_.items.reserve(16);
  mission_.items.push_back(MissionItem{});  // item 0: home
}

void FlightController::Impl::set_home(const Eigen::Vector3d& home) {
  home_.position_enu_m = home;
  home_.set = true;
  // mission item 0 is home, as in ArduPilot
  if (!mission_.items.empty()) mission_.items[0].position_enu_m = home;
}

ModeContext FlightController::Impl::mode_context() {
  return ModeContext({estimator_.state(), now(), params_, home_},
                     {flight_, command_, yaw_, nav_, pilot_, guided_, mission_, texts_}, *this);
}

void FlightController::Impl::restart_for_takeoff() {
  land_detect_s_ = 0.0;
  pos_ctrl_.reset();
  att_ctrl_.reset();
}

void FlightController::Impl::update(double time_s, const TruthState& truth,
                                    const airframe::BatteryState& battery, double* motor_cmd) {
  const std::size_t n = mixer_.rotor_count();
  // reject non-finite input: repeat the previous commands, count it
  if (!std::isfinite(time_s) || !finite(truth) || !std::isfinite(battery.consumed_mah)) {
    ++nonfinite_inputs_;
    for (std::size_t k = 0; k < n; ++k) motor_cmd[k] = flight_.armed ? motor_cmd_[k] : 0.0;
    return;
  }
  // dt from successive sim times
  double dt_s = have_time_ ? std::clamp(time_s - last_time_s_, 0.0, kMaxDtS) : 0.0;
  last_time_s_ = time_s;
  have_time_ = true;
  battery_ = battery;

  // sense and estimate
  sensors_.sample(time_s, truth, params_.values(), &frame_);
  estimator_.update(time_s, dt_s, frame_);
  const EstimatedState& est = estimator_.state();
  estimator_converged_ = estimator_.converged(time_s);
  // home at the first good fix, until arming sets it again
  if (!home_.set && est.gps_ok && estimator_converged_) set_home(est.position_enu_m);

  if (dt_s <= 0.0) {
    for (std::size_t k = 0; k < n; ++k) motor_cmd[k] = flight_.armed ? motor_cmd_[k] : 0.0;
    return;
  }

  // failsafes, then the mode's setpoints, then the cascade
  run_failsafes();
  if (flight_.armed) {
    monitor_motors(dt_s);
    run_mode(dt_s);
    update_yaw(dt_s);
    run_land_detector(dt_s);
  }
  if (!flight_.armed) {
    pos_ctrl_.reset();
    att_ctrl_.reset();
    for (std::size_t k = 0; k < n; ++k) motor_cmd_[k] = 0.0;
  } else if (command_.kind == ControlKind::kIdle) {
    // on the ground: spin at MOT_SPIN_ARM, keep the controllers fresh for take-off
    pos_ctrl_.reset();
    att_ctrl_.reset();
    yaw_.target_rad = estimator_.yaw_enu_rad();
    yaw_.cmd_rad = yaw_.target_rad;
    for (std::size_t k = 0; k < n; ++k) motor_cmd_[k] = params_.values().mot_spin_arm;
    mixer_status_ = MixerStatus{};
    mixer_status_.thrust_n = 0.0;
  } else {
    run_cascade(dt_s);
  }
  for (std::size_t k = 0; k < n; ++k) motor_cmd[k] = motor_cmd_[k];
}

void FlightController::Impl::monitor_motors(double dt_s) {
  // (commands of the last step, IMU now) => a lost rotor, once, then the degraded mixer
  const double height =
      estimator_.state().position_enu_m.z() - (home_.set ? home_.position_enu_m.z() : 0.0);
  const bool airborne = !flight_.landed && command_.kind != ControlKind::kIdle &&
                        height > kMonitorMinHeightM &&
                        collective_demand_n_ > kMonitorMinThrustFraction * hover_thrust_n_;
  motor_monitor_.update(motor_cmd_.data(), frame_.imu.gyro_body_rad_s, frame_.imu.accel_body_m_s2,
                        dt_s, airborne);
  const int lost = motor_monitor_.lost_rotor();
  if (lost < 0 || lost_motor_ >= 0) return;
  if (static_cast<std::size_t>(lost) >= degraded_mixers_.size() ||
      !degraded_mixers_[static_cast<std::size_t>(lost)]) {
    return;
  }
  lost_motor_ = lost;
  // the rate integrators wound up against the lost torque: with the new mixer they only disturb
  att_ctrl_.reset_integrators();
  char text[51];
  std::snprintf(text, sizeof(text), "Thrust loss: motor %d, yaw released", lost + 1);
  status(2, text);
}

void FlightController::Impl::update_yaw(double dt_s) {
  const DerivedParams& d = params_.derived();
  // No command turns the vehicle faster than ATC_RATE_Y_MAX (a GUIDED yaw rate or a CONDITION_YAW
  // rate above it is flown at it, as ArduCopter does). The command also never leads the vehicle by
  // more than the heading error at which the angle loop already asks that rate: a heading command
  // running away from a vehicle that cannot follow (a 30 rad/s GUIDED yaw rate once did) reaches
  // errors near 180 deg, where the shortest rotation to the attitude target tilts the vehicle as
  // much as it turns it, and the copter tumbled.
  const double rate_max = d.rate_y_max_rad_s;
  const double p = params_.values().atc_ang_yaw_p;
  const double lead_max = p > 0.0 ? std::min(rate_max / p, kPi / 2.0) : kPi / 2.0;
  const double yaw_now = estimator_.yaw_enu_rad();
  auto within_lead = [&](double yaw) {
    return wrap_pi(yaw_now + std::clamp(wrap_pi(yaw - yaw_now), -lead_max, lead_max));
  };
  // yaw-rate mode integrates the rate; otherwise slew the command toward the target
  if (yaw_.rate_mode) {
    const double rate = std::clamp(yaw_.rate_cmd_rad_s, -rate_max, rate_max);
    yaw_.target_rad = within_lead(wrap_pi(yaw_.target_rad + rate * dt_s));
    yaw_.cmd_rad = yaw_.target_rad;
    yaw_.rate_ff_rad_s = rate;
    return;
  }
  const double slew = std::min(
      yaw_.slew_override_rad_s > 0.0 ? yaw_.slew_override_rad_s : d.slew_yaw_rad_s, rate_max);
  const double err = wrap_pi(yaw_.target_rad - yaw_.cmd_rad);
  const double step = std::clamp(err, -slew * dt_s, slew * dt_s);
  const double cmd = within_lead(wrap_pi(yaw_.cmd_rad + step));
  yaw_.rate_ff_rad_s = wrap_pi(cmd - yaw_.cmd_rad) / dt_s;
  yaw_.cmd_rad = cmd;
}

void FlightController::Impl::run_cascade(double dt_s) {
  const ParamValues& p = params_.values();
  const DerivedParams& d = params_.derived();
  const EstimatedState& est = estimator_.state();

  // outer loops: a thrust vector and an attitude target
  Eigen::Vector3d torque_body_nm;
  double collective_n = 0.0;
  const RateLimits rate_limits{mixer_status_.roll_pitch_scale < 1.0, mixer_status_.yaw_scale < 1.0};
  const ThrustLimits thrust_limits{mixer_status_.limit_thrust_up, mixer_status_.limit_thrust_down};
  // a lost rotor: yaw is no longer controlled, the heading target follows the vehicle (it may turn)
  // and only the yaw rate is damped as far as the degraded mixer allows
  if (lost_motor_ >= 0) {
    yaw_.target_rad = estimator_.yaw_enu_rad();
    yaw_.cmd_rad = yaw_.target_rad;
    yaw_.rate_ff_rad_s = 0.0;
  }
  const Eigen::Vector3d z_body_enu = est.q_enu_body * Eigen::Vector3d::UnitZ();
  // the collective that gives the demanded vertical thrust at the current tilt
  const double cos_tilt = std::max(z_body_enu.z(), 0.5);
  if (command_.kind == ControlKind::kPosition) {
    const Eigen::Vector3d thrust_enu =
        pos_ctrl_.update(est, estimator_.accel_z_filtered_m_s2(), command_.setpoint, p, d, mass_kg_,
                         dt_s, thrust_limits);
    command_.q_attitude_target = attitude_from_thrust(thrust_enu, yaw_.cmd_rad, d.angle_max_rad);
    collective_n = thrust_enu.z() / cos_tilt;
    torque_body_nm =
        att_ctrl_.update(command_.q_attitude_target, yaw_.rate_ff_rad_s, est.q_enu_body,
                         est.rate_body_rad_s, inertia_, p, d, dt_s, rate_limits);
  } else {
    // attitude or body rates given; collective from the climb-rate controller or held fixed
    if (command_.attitude_climb) {
      const Eigen::Vector3d thrust_enu =
          pos_ctrl_.update(est, estimator_.accel_z_filtered_m_s2(), command_.setpoint, p, d,
                           mass_kg_, dt_s, thrust_limits);
      collective_n = thrust_enu.z() / cos_tilt;
    } else {
      collective_n = command_.fixed_thrust_n;
    }
    if (command_.kind == ControlKind::kBodyRate) {
      torque_body_nm = att_ctrl_.update_rate(command_.rate_target_body_rad_s, est.rate_body_rad_s,
                                             inertia_, p, dt_s, rate_limits);
    } else {
      torque_body_nm =
          att_ctrl_.update(command_.q_attitude_target, yaw_.rate_ff_rad_s, est.q_enu_body,
                           est.rate_body_rad_s, inertia_, p, d, dt_s, rate_limits);
    }
  }
  // low collective demand: ground contact is likely, relax the rate integrators (ArduCopter)
  collective_demand_n_ = collective_n;
  if (collective_n < kRelaxThrustFraction * hover_thrust_n_) att_ctrl_.relax_i(dt_s, kRelaxTauS);
  // mixer: per-rotor thrust, then the inverse square law
  const Mixer& mixer = active_mixer();
  collective_n = std::clamp(collective_n, 0.0, mixer.max_total_thrust_n());
  mixer_status_ = mixer.mix(torque_body_nm, collective_n, rotor_thrust_n_.data(), motor_cmd_.data());
}

// ---------------------------------------------------------------------------------------------------
// FlightController: thin forwarding and commands

FlightController::FlightController(const airframe::AirframeParams& airframe, uint64_t seed)
    : impl_(std::make_unique<Impl>(airframe, seed)) {}
FlightController::~FlightController() = default;
FlightController::FlightController(FlightController&&) noexcept = default;
FlightController& FlightController::operator=(FlightController&&) noexcept = default;

void FlightController::update(double time_s, const TruthState& truth,
                              const airframe::BatteryState& battery, double* motor_cmd) {
  impl_->update(time_s, truth, battery, motor_cmd);
}

CommandResult FlightController::arm(bool force) {
  Impl& s = *impl_;
  if (s.flight_.armed) return CommandResult::kAccepted;
  // modes that cannot arm refuse even a forced arm (ArduCopter's allows_arming)
  if (!s.active_mode().allows_arming()) {
    s.status(2, std::string("Arm: Mode not armable (") + mode_name(s.mode_) + ")");
    return CommandResult::kDenied;
  }
  if (!force && s.params_.values().arming_check > 0.0 && !s.prearm_checks(true)) {
    return CommandResult::kDenied;
  }
  s.flight_.armed = true;
  s.flight_.landed = true;
  s.flight_.takeoff_active = false;
  s.landed_since_s_ = s.now();
  s.land_detect_s_ = 0.0;
  s.fs_gcs_active_ = false;
  s.fs_batt_triggered_ = false;
  s.fs_ekf_active_ = false;
  s.motor_monitor_.reset();
  s.lost_motor_ = -1;
  s.command_.kind = ControlKind::kIdle;
  s.yaw_.target_rad = s.estimator_.yaw_enu_rad();
  s.yaw_.cmd_rad = s.yaw_.target_rad;
  // home where we arm (ArduCopter sets home at arming)
  if (s.estimator_.position_ok()) s.set_home(s.estimator_.state().position_enu_m);
  s.init_mode_state();
  s.status(6, "Arming motors");
  return CommandResult::kAccepted;
}

CommandResult FlightController::disarm(bool force) {
  Impl& s = *impl_;
  if (!s.flight_.armed) return CommandResult::kAccepted;
  if (!force && !s.flight_.landed) {
    s.status(4, "Disarm: vehicle not landed");
    return CommandResult::kDenied;
  }
  s.do_disarm("Disarming motors");
  return CommandResult::kAccepted;
}

CommandResult FlightController::set_mode(Mode mode) {
  return impl_->enter_mode(mode, false) ? CommandResult::kAccepted : CommandResult::kFailed;
}

CommandResult FlightController::takeoff(double altitude_above_home_m) {
  Impl& s = *impl_;
  if (!std::isfinite(altitude_above_home_m)) return CommandResult::kInvalid;
  if (altitude_above_home_m <= 0.0) altitude_above_home_m = s.params_.derived().pilot_tkoff_alt_m;
  if (altitude_above_home_m <= 0.0) return CommandResult::kInvalid;
  if (!s.flight_.armed) return CommandResult::kDenied;
  // user take-off: GUIDED, LOITER, ALT_HOLD, only from the ground, only upward
  if (s.mode_ != Mode::kGuided && s.mode_ != Mode::kLoiter && s.mode_ != Mode::kAltHold) {
    return CommandResult::kFailed;
  }
  if (!s.flight_.landed) return CommandResult::kFailed;
  const double base_z =
      s.home_.set ? s.home_.position_enu_m.z() : s.estimator_.state().position_enu_m.z();
  const double target_z = base_z + altitude_above_home_m;
  if (target_z <= s.estimator_.state().position_enu_m.z()) return CommandResult::kFailed;
  s.mode_context().start_takeoff(target_z);
  if (s.mode_ == Mode::kGuided) s.guided_.sub = GuidedSub::kTakeoff;
  return CommandResult::kAccepted;
}

CommandResult FlightController::set_guided_target(const GuidedTarget& t) {
  Impl& s = *impl_;
  // reject non-finite values and absurd speeds
  if ((t.position_enu_m && !finite(*t.position_enu_m)) ||
      (t.velocity_enu_m_s && !finite(*t.velocity_enu_m_s)) ||
      (t.accel_enu_m_s2 && !finite(*t.accel_enu_m_s2)) ||
      (t.yaw_enu_rad && !std::isfinite(*t.yaw_enu_rad)) ||
      (t.yaw_rate_rad_s && !std::isfinite(*t.yaw_rate_rad_s))) {
    return CommandResult::kInvalid;
  }
  if (t.velocity_enu_m_s && t.velocity_enu_m_s->norm() > kMaxGuidedSpeedM_S) {
    return CommandResult::kInvalid;
  }
  if (s.mode_ != Mode::kGuided) return CommandResult::kDenied;
  s.guided_.target = t;
  s.guided_.cmd_time_s = s.now();
  s.guided_.is_new = true;
  // yaw: a heading, a rate, or keep the current behaviour
  if (t.yaw_enu_rad) {
    s.yaw_.target_rad = wrap_pi(*t.yaw_enu_rad);
    s.yaw_.fixed = true;
    s.yaw_.rate_mode = false;
    s.yaw_.slew_override_rad_s = 0.0;
  } else if (t.yaw_rate_rad_s) {
    s.yaw_.rate_cmd_rad_s = *t.yaw_rate_rad_s;
    s.yaw_.rate_mode = true;
    s.yaw_.fixed = true;
  }
  // dispatch as ArduCopter: pos+vel(+acc), vel(+acc), acc, pos, else hold
  const bool landed = s.flight_.landed || !s.flight_.armed;
  const GuidedSub old_sub = s.guided_.sub;
  if (t.position_enu_m && (t.velocity_enu_m_s || t.accel_enu_m_s2)) {
    s.guided_.sub = GuidedSub::kPosVelAccel;
    s.nav_.active = false;
  } else if (t.velocity_enu_m_s) {
    s.guided_.sub = GuidedSub::kVelAccel;
    s.nav_.active = false;
  } else if (t.accel_enu_m_s2) {
    s.guided_.sub = GuidedSub::kAccel;
    s.nav_.active = false;
  } else if (t.position_enu_m) {
    s.guided_.sub = GuidedSub::kWp;
    s.flight_.takeoff_active = s.flight_.takeoff_active && landed;
    if (!landed) s.mode_context().start_nav_to(*t.position_enu_m);
  } else if (!t.yaw_enu_rad && !t.yaw_rate_rad_s) {
    s.guided_.sub = GuidedSub::kHold;
    if (!landed) s.mode_context().start_hold();
  }
  s.guided_.reinit = s.guided_.reinit || s.guided_.sub != old_sub;
  return CommandResult::kAccepted;
}

CommandResult FlightController::set_attitude_target(const AttitudeTarget& t) {
  Impl& s = *impl_;
  if ((t.q_enu_body && (!t.q_enu_body->coeffs().allFinite() || t.q_enu_body->norm() < 0.5)) ||
      (t.rate_body_rad_s && !finite(*t.rate_body_rad_s)) || !std::isfinite(t.thrust) ||
      t.thrust < 0.0 || t.thrust > 1.0) {
    return CommandResult::kInvalid;
  }
  if (!t.q_enu_body && !t.rate_body_rad_s) return CommandResult::kInvalid;
  if (s.mode_ != Mode::kGuided) return CommandResult::kDenied;
  s.guided_.attitude = t;
  if (t.q_enu_body) s.guided_.attitude.q_enu_body = t.q_enu_body->normalized();
  s.guided_.cmd_time_s = s.now();
  s.guided_.sub = GuidedSub::kAttitude;
  s.nav_.active = false;
  return CommandResult::kAccepted;
}

CommandResult FlightController::set_pilot_input(const PilotInput& in, double time_s) {
  Impl& s = *impl_;
  const bool finite_in = std::isfinite(in.roll) && std::isfinite(in.pitch) && std::isfinite(in.yaw) &&
                         std::isfinite(in.throttle) && std::isfinite(time_s);
  if (!finite_in || std::abs(in.roll) > 1.0 || std::abs(in.pitch) > 1.0 || std::abs(in.yaw) > 1.0 ||
      in.throttle < 0.0 || in.throttle > 1.0) {
    return CommandResult::kInvalid;
  }
  if (s.params_.values().rc_override_time == 0.0) return CommandResult::kDenied;
  s.pilot_.input = in;
  s.pilot_.time_s = time_s;
  return CommandResult::kAccepted;
}

std::optional<PilotInput> FlightController::Impl::pilot() const {
  if (!active_mode().reads_pilot()) return std::nullopt;
  return fresh_pilot_input(pilot_, params_.values(), now());
}

CommandResult FlightController::set_yaw(const YawCommand& command) {
  Impl& s = *impl_;
  if (!std::isfinite(command.yaw_enu_rad) || !std::isfinite(command.rate_rad_s) || command.rate_rad_s < 0.0) {
    return CommandResult::kInvalid;
  }
  if (!s.flight_.armed) return CommandResult::kFailed;
  const double target =
      command.relative ? s.yaw_.target_rad + command.yaw_enu_rad : command.yaw_enu_rad;
  s.yaw_.target_rad = wrap_pi(target);
  s.yaw_.fixed = true;
  s.yaw_.rate_mode = false;
  s.yaw_.slew_override_rad_s = command.rate_rad_s;
  return CommandResult::kAccepted;
}

CommandResult FlightController::change_speed(SpeedLimit limit, double speed_m_s) {
  Impl& s = *impl_;
  if (!std::isfinite(speed_m_s) || speed_m_s <= 0.0 || speed_m_s > 50.0) {
    return CommandResult::kInvalid;
  }
  switch (limit) {
    case SpeedLimit::kHorizontal:
      s.nav_.speed_xy_override_m_s = speed_m_s;
      break;
    case SpeedLimit::kClimb:
      s.nav_.speed_up_override_m_s = speed_m_s;
      break;
    case SpeedLimit::kDescent:
      s.nav_.speed_dn_override_m_s = speed_m_s;
      break;
    default: return CommandResult::kInvalid;
  }
  return CommandResult::kAccepted;
}

CommandResult FlightController::land() { return set_mode(Mode::kLand); }
CommandResult FlightController::rtl() { return set_mode(Mode::kRtl); }

void FlightController::set_mission(std::vector<MissionItem> items) {
  Impl& s = *impl_;
  s.mission_.items = std::move(items);
  if (s.mission_.items.empty()) s.mission_.items.push_back(MissionItem{});
  if (s.home_.set) s.mission_.items[0].position_enu_m = s.home_.position_enu_m;
  s.mission_.current = 1;
  s.mission_.last = -1;
  // a new mission under a flying AUTO: ArduCopter restarts it from item 1
  if (s.mode_ == Mode::kAuto && s.flight_.armed && !s.flight_.landed) s.start_mission_item(1);
}

const std::vector<MissionItem>& FlightController::mission() const { return impl_->mission_.items; }

CommandResult FlightController::mission_start(int first_item, int last_item) {
  Impl& s = *impl_;
  const int size = static_cast<int>(s.mission_.items.size());
  if (first_item < 0 || last_item < 0 || first_item >= size || last_item >= size) {
    return CommandResult::kInvalid;
  }
  if (size < 2) return CommandResult::kFailed;
  s.mission_.current = first_item > 0 ? first_item : 1;
  s.mission_.last = last_item > 0 ? last_item : -1;
  if (s.mode_ == Mode::kAuto) {
    s.start_mission_item(s.mission_.current);
    return CommandResult::kAccepted;
  }
  return set_mode(Mode::kAuto);
}

CommandResult FlightController::set_mission_current(int seq) {
  Impl& s = *impl_;
  if (seq < 0 || seq >= static_cast<int>(s.mission_.items.size())) return CommandResult::kInvalid;
  s.mission_.current = std::max(seq, 1);
  if (s.mode_ == Mode::kAuto && s.flight_.armed) s.start_mission_item(s.mission_.current);
  return CommandResult::kAccepted;
}

int FlightController::mission_current() const { return impl_->mission_.current; }

std::vector<int> FlightController::drain_reached_items() {
  std::vector<int> out;
  impl_->mission_.reached.drain([&out](int seq) { out.push_back(seq); });
  return out;
}

std::optional<double> FlightController::param(std::string_view name) const {
  return impl_->params_.get(name);
}

std::optional<ParamKind> FlightController::param_kind(std::string_view name) const {
  return impl_->params_.kind(name);
}

CommandResult FlightController::set_param(std::string_view name, double value) {
  return impl_->params_.set(name, value) ? CommandResult::kAccepted : CommandResult::kInvalid;
}

const std::vector<std::string>& FlightController::param_names() const {
  return impl_->params_.names();
}

void FlightController::on_gcs_heartbeat(double time_s) {
  Impl& s = *impl_;
  if (!std::isfinite(time_s)) return;
  s.gcs_seen_ = true;
  s.last_gcs_heartbeat_s_ = time_s;
  if (s.fs_gcs_active_) {
    s.fs_gcs_active_ = false;
    s.status(6, "GCS Failsafe Cleared");
  }
}

void FlightController::set_gps_denied(bool denied) { impl_->sensors_.set_gps_denied(denied); }

void FlightController::set_gps_glitch(const Eigen::Vector3d& offset_enu_m) {
  if (offset_enu_m.allFinite()) impl_->sensors_.set_gps_glitch(offset_enu_m);
}

Mode FlightController::mode() const { return impl_->mode_; }
bool FlightController::armed() const { return impl_->flight_.armed; }

LandedState FlightController::landed_state() const {
  const Impl& s = *impl_;
  if (!s.flight_.armed || s.flight_.landed) return LandedState::kOnGround;
  if (s.flight_.takeoff_active) return LandedState::kTakeoff;
  return s.active_mode().landing() ? LandedState::kLanding : LandedState::kInAir;
}

const EstimatedState& FlightController::estimate() const { return impl_->estimator_.state(); }
Eigen::Vector3d FlightController::home_enu_m() const { return impl_->home_.position_enu_m; }
bool FlightController::home_set() const { return impl_->home_.set; }

std::optional<GuidedTarget> FlightController::current_target() const {
  const Impl& s = *impl_;
  if (!s.flight_.armed || s.command_.kind == ControlKind::kIdle) return std::nullopt;
  if (s.command_.kind != ControlKind::kPosition && !s.command_.attitude_climb) return std::nullopt;
  GuidedTarget t;
  if (s.command_.kind == ControlKind::kPosition && s.command_.setpoint.use_pos_xy &&
      s.command_.setpoint.use_pos_z) {
    t.position_enu_m = s.command_.setpoint.position_enu_m;
  }
  t.velocity_enu_m_s = s.pos_ctrl_.velocity_target();
  t.accel_enu_m_s2 = s.pos_ctrl_.accel_target();
  t.yaw_enu_rad = s.yaw_.cmd_rad;
  return t;
}

double FlightController::yaw_target_enu_rad() const { return impl_->yaw_.target_rad; }
bool FlightController::prearm_ok() const { return impl_->prearm_checks(false); }

std::vector<StatusText> FlightController::drain_status_texts() {
  std::vector<StatusText> out;
  impl_->texts_.drain([&out](const FixedText& t) {
    out.push_back(StatusText{t.severity, std::string(t.text.data())});
  });
  return out;
}

uint64_t FlightController::nonfinite_input_count() const { return impl_->nonfinite_inputs_; }

}  // namespace uavsim::server::fc
