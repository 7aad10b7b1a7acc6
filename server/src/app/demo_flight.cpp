#include "app/demo_flight.hpp"

#include <array>
#include <cstdio>

namespace uavsim::server::app {

namespace {

constexpr double kAltitudeM = 10.0;
constexpr double kReachedM = 1.0;          // a waypoint counts when passed within 1 m
constexpr double kTimeoutS = 240.0;        // the whole flight, in sim time
constexpr double kReportPeriodS = 2.0;
const std::array<Eigen::Vector3d, 3> kWaypointsEnu = {
    Eigen::Vector3d(20, 0, kAltitudeM), Eigen::Vector3d(20, 20, kAltitudeM),
    Eigen::Vector3d(0, 20, kAltitudeM)};

}  // namespace

DemoFlight::DemoFlight(std::ostream& out, bool quiet) : out_(out), quiet_(quiet) {}

void DemoFlight::on_control_step(sim::Simulation& sim) {
  if (finished_ || sim.vehicle_count() == 0) return;
  const double t = sim.time_s();
  const fc::FlightController& fc = sim.fc(0);
  const fc::TruthState truth = sim.truth(0);
  result_.max_altitude_m = std::max(result_.max_altitude_m, truth.position_enu_m.z());

  if (!quiet_ && t >= next_report_s_) {
    next_report_s_ += kReportPeriodS;
    char line[200];
    std::snprintf(line, sizeof(line), "t=%6.1fs  %-8s %-8s alt=%6.2f m  pos=(%6.2f, %6.2f)  battery %5.1f%%",
                  t, fc::mode_name(fc.mode()), fc.armed() ? "armed" : "disarmed", truth.position_enu_m.z(),
                  truth.position_enu_m.x(), truth.position_enu_m.y(),
                  100.0 * airframe::battery_remaining(sim.airframe(0), sim.runtime(0).battery));
    out_ << line << "\n";
  }
  if (sim.runtime(0).crashed) return finish(false, "the vehicle crashed");
  if (t > kTimeoutS) return finish(false, "timed out");

  switch (phase_) {
    case Phase::kWaitGps:
      if (fc.prearm_ok()) phase_ = Phase::kArm;
      break;
    case Phase::kArm:
      // GUIDED, arm, take off: three commands in one control step, in order
      sim.post(0, [](fc::FlightController& f) {
        f.set_mode(fc::Mode::kGuided);
        f.arm(false);
        f.takeoff(kAltitudeM);
      });
      if (!quiet_) out_ << "t=" << t << "s  arming in GUIDED and taking off to " << kAltitudeM << " m\n";
      takeoff_time_s_ = t;
      phase_ = Phase::kClimb;
      break;
    case Phase::kClimb:
      if (truth.position_enu_m.z() > kAltitudeM - 0.5) phase_ = Phase::kWaypoints;
      if (t - takeoff_time_s_ > 2.0 && !fc.armed()) return finish(false, "arming or take-off refused");
      break;
    case Phase::kWaypoints: {
      const Eigen::Vector3d wp = kWaypointsEnu[waypoint_];
      if (!fc.current_target() || !fc.current_target()->position_enu_m ||
          (*fc.current_target()->position_enu_m - wp).norm() > 1e-6) {
        sim.post(0, [wp](fc::FlightController& f) {
          fc::GuidedTarget target;
          target.position_enu_m = wp;
          f.set_guided_target(target);
        });
      }
      if ((truth.position_enu_m - wp).norm() < kReachedM) {
        ++result_.waypoints_reached;
        if (!quiet_) out_ << "t=" << t << "s  reached waypoint " << waypoint_ + 1 << "\n";
        if (++waypoint_ == kWaypointsEnu.size()) {
          sim.post(0, [](fc::FlightController& f) { f.land(); });
          phase_ = Phase::kLanding;
        }
      }
      break;
    }
    case Phase::kLanding:
      if (!fc.armed()) {
        result_.flight_time_s = t - takeoff_time_s_;
        if (!quiet_) out_ << "t=" << t << "s  landed and disarmed\n";
        finish(true, "");
      }
      break;
    case Phase::kDone:
      break;
  }
  result_.battery_used_mah = sim.runtime(0).battery.consumed_mah;
}

void DemoFlight::finish(bool success, const std::string& failure) {
  result_.success = success;
  result_.failure = failure;
  finished_ = true;
  phase_ = Phase::kDone;
}

void DemoFlight::print_summary(std::ostream& out) const {
  char line[300];
  std::snprintf(line, sizeof(line),
                "RESULT: %s  waypoints %d/3, flight time %.1f s, max altitude %.2f m, battery used %.0f mAh%s%s\n",
                result_.success ? "PASS" : "FAIL", result_.waypoints_reached, result_.flight_time_s,
                result_.max_altitude_m, result_.battery_used_mah, result_.failure.empty() ? "" : " — ",
                result_.failure.c_str());
  out << line;
}

}  // namespace uavsim::server::app
