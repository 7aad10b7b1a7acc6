#include "app/hover_all.hpp"

#include <cmath>

namespace uavsim::server::app {

HoverAll::HoverAll(double altitude_m, std::ostream& out, bool quiet)
    : altitude_m_(altitude_m), out_(out), quiet_(quiet) {}

void HoverAll::on_control_step(sim::Simulation& sim) {
  const std::size_t n = sim.vehicle_count();
  if (commanded_.size() != n) {  // the first step, or after a reset
    commanded_.assign(n, false);
    reached_.assign(n, false);
    reached_count_ = 0;
    all_reported_ = false;
  }
  for (std::size_t i = 0; i < n; ++i) {
    if (!commanded_[i]) {
      if (!sim.fc(i).prearm_ok()) continue;  // GPS and EKF not ready yet: the arm would be refused
      const double altitude_m = altitude_m_;
      // GUIDED, arm, take off: in one control step, in this order (as a ground station would)
      sim.post(i, [altitude_m](fc::FlightController& f) {
        f.set_mode(fc::Mode::kGuided);
        f.arm(false);
        f.takeoff(altitude_m);
      });
      commanded_[i] = true;
    } else if (!reached_[i] && sim.truth(i).position_enu_m.z() > altitude_m_ - kReachedM) {
      reached_[i] = true;
      ++reached_count_;
    }
  }
  if (!all_reported_ && n > 0 && reached_count_ == n) {
    all_reported_ = true;
    if (!quiet_) {
      out_ << "uavsim-server: --hover: all " << n << " vehicle(s) at " << altitude_m_
           << " m by t=" << std::round(sim.time_s() * 100.0) / 100.0 << " s\n";
      out_.flush();
    }
  }
}

}  // namespace uavsim::server::app
