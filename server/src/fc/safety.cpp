// Safety logic: pre-arm checks, the land detector with auto-disarm, and the GCS-loss, battery and
// GPS-loss failsafes.
#include <cmath>
#include <string>

#include "fc/fc_impl.hpp"
#include "fc/flight_controller.hpp"

namespace uavsim::server::fc {

namespace {
// ArduCopter land detector (land_detector.cpp): thrust low, vertical speed and acceleration small,
// held for LAND_DETECTOR_TRIGGER_SEC
constexpr double kLandThrustFraction = 0.25;  // of hover thrust
constexpr double kLandMaxClimbM_S = 1.0;
constexpr double kLandMaxAccelM_S2 = 1.0;
constexpr double kLandTriggerS = 1.0;
// GPS lost this long in a position mode triggers the EKF failsafe
constexpr double kGpsLossFailsafeS = 1.0;
}  // namespace

bool FlightController::Impl::prearm_checks(bool report) const {
  const EstimatedState& est = estimator_.state();
  const char* fail = nullptr;
  // with a GPS fix the position estimate must settle before arming in any mode (so that a GPS mode can
  // be entered right after); without GPS only the modes that need position wait for it
  if (!estimator_.attitude_ok() || (!estimator_converged_ && (gps_mode(mode_) || est.gps_ok))) {
    fail = "PreArm: EKF not converged";
  } else if (gps_mode(mode_) && !est.gps_ok) {
    fail = "PreArm: GPS no 3D fix";
  } else if (gps_mode(mode_) && !home_.set) {
    fail = "PreArm: home not set";
  } else if (params_.values().batt_capacity > 0.0 &&
             battery_.consumed_mah >= params_.values().batt_capacity) {
    fail = "PreArm: battery empty";
  } else if (!flight_.landed) {
    fail = "PreArm: not landed";
  }
  if (fail != nullptr && report) status(2, fail);
  return fail == nullptr;
}

void FlightController::Impl::do_disarm(std::string_view why) {
  flight_.armed = false;
  flight_.landed = true;
  flight_.takeoff_active = false;
  nav_.active = false;
  command_.kind = ControlKind::kIdle;
  pos_ctrl_.reset();
  att_ctrl_.reset();
  status(6, why);
}

void FlightController::Impl::on_touchdown() {
  flight_.landed = true;
  landed_since_s_ = now();
  nav_.active = false;
  status(6, "Landed");
  // LAND, RTL and a mission's land or RTL disarm at touchdown; other modes wait DISARM_DELAY
  const bool landing_mode = active_mode().ends_flight_at_touchdown();
  if (mode_ == Mode::kAuto && landing_mode) {
    mission_.reached.push(mission_.current);
    modes_.automatic.finish();
  }
  if (landing_mode) do_disarm("Disarming motors: landed");
}

void FlightController::Impl::run_land_detector(double dt_s) {
  if (!flight_.armed || flight_.landed || flight_.takeoff_active) {
    land_detect_s_ = 0.0;
    return;
  }
  const EstimatedState& est = estimator_.state();
  // ArduCopter: throttle demand at its lower limit. Not the mixer raising thrust for torque: that
  // happens in the air too (a failed rotor) and would disarm a flying vehicle.
  const bool thrust_low = collective_demand_n_ < kLandThrustFraction * hover_thrust_n_;
  const bool still = std::abs(est.velocity_enu_m_s.z()) < kLandMaxClimbM_S &&
                     std::abs(estimator_.accel_z_filtered_m_s2()) < kLandMaxAccelM_S2;
  land_detect_s_ = (thrust_low && still) ? land_detect_s_ + dt_s : 0.0;
  if (land_detect_s_ >= kLandTriggerS) {
    land_detect_s_ = 0.0;
    on_touchdown();
  }
}

void FlightController::Impl::run_failsafes() {
  if (!flight_.armed) return;
  const ParamValues& p = params_.values();
  const EstimatedState& est = estimator_.state();

  // GCS loss: only once a GCS has been heard, only in GUIDED and AUTO
  if (gcs_seen_ && p.fs_gcs_enable > 0.0 && !fs_gcs_active_ &&
      now() - last_gcs_heartbeat_s_ > p.fs_gcs_timeout &&
      (mode_ == Mode::kGuided || mode_ == Mode::kAuto)) {
    fs_gcs_active_ = true;
    status(2, "GCS Failsafe");
    if (flight_.landed) {
      do_disarm("Disarming motors: GCS failsafe");
      return;
    }
    if (!enter_mode(Mode::kRtl, true)) enter_mode(Mode::kLand, true);
  }

  // battery: remaining below BATT_LOW_MAH
  const double remaining_mah = p.batt_capacity - battery_.consumed_mah;
  if (p.fs_batt_enable > 0.0 && !fs_batt_triggered_ && p.batt_capacity > 0.0 &&
      remaining_mah < p.batt_low_mah) {
    fs_batt_triggered_ = true;
    status(2, "Battery failsafe");
    if (flight_.landed) {
      do_disarm("Disarming motors: battery failsafe");
      return;
    }
    if (mode_ != Mode::kLand) {
      if (p.fs_batt_enable < 1.5 || !enter_mode(Mode::kRtl, true)) enter_mode(Mode::kLand, true);
    }
  }

  // GPS lost in a position mode: land (ArduCopter's EKF failsafe, FS_EKF_ACTION = 1)
  if (gps_mode(mode_) && !flight_.landed && !est.gps_ok) {
    if (gps_lost_since_s_ < 0.0) gps_lost_since_s_ = now();
    if (p.fs_ekf_action > 0.0 && !fs_ekf_active_ && now() - gps_lost_since_s_ >= kGpsLossFailsafeS) {
      fs_ekf_active_ = true;
      status(2, "EKF Failsafe: GPS lost, LAND");
      enter_mode(Mode::kLand, true);
    }
  } else {
    gps_lost_since_s_ = -1.0;
  }
}

}  // namespace uavsim::server::fc
