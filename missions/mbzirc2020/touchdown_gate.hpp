// Whether a landing UAV may go on with its last metres of descent, from what its telemetry says
// (velocity, attitude): a gusty wind must not put it down with sideways speed, nor with its skids
// across the wind. The quad's gear is two skids along body x, 0.2 m apart, under a centre of mass
// 0.16 m above them (models/vehicles/quad.xml): about a skid it tips past atan(0.1 / 0.16) = 32
// deg, and less with the wind pushing (at 8-9 m/s, a gust on the field's 4 m/s, the airframe's drag
// is ~4.5 N, 0.3 of the weight, which leaves 0.1 - 0.3 * 0.16 = 0.05 m of lever: ~16 deg). Two-UAV
// field seeds 1 and 12 tipped over so at touchdown: one touched down with 1 m/s sideways at -22 deg
// of roll, the other with 0.4 m/s and rocked over a skid after the motors were off. About the
// skids' ends (0.12 m from the centre) the vehicle needs 0.04 m of rise to tip instead of 0.029 m,
// and the wind's push along the skids does not roll it: the descent lays the skids along the wind.
//
// The wind's direction comes from the hover's lean: holding still, the thrust tilts into the wind
// by atan(drag / weight) (4.7 deg at 4 m/s); its low-passed horizontal direction points upwind.
// Pure: tests feed it synthetic telemetry.
#pragma once

#include <Eigen/Core>
#include <optional>

#include "uavsim/common/angles.hpp"

namespace uavsim::missions::mbzirc2020 {

struct TouchdownGateConfig {
  double pause_speed_m_s = 0.5;  // horizontal speed over this: stop descending
  double calm_speed_m_s = 0.25;  // go on once under this ...
  double calm_for_s = 1.0;       // ... for this long
  double wind_tau_s = 3.0;       // low-pass of the lean that estimates the wind
  double wind_min_tilt_rad = 2.0 * common::kPi / 180.0;  // less: wind unknown
  double max_pause_s = 20.0;  // paused this long in all: descend whatever the wind does
};

class TouchdownGate {
 public:
  explicit TouchdownGate(const TouchdownGateConfig& config = {}) : config_(config) {}

  void reset();
  // One telemetry sample (ATTITUDE in NED: roll positive right wing down, pitch positive nose up;
  // the heading in ENU). Returns whether the descent may go on.
  bool update(double now_s, const Eigen::Vector2d& velocity_enu_m_s, double roll_rad,
              double pitch_rad, double yaw_enu_rad);
  // The heading nearest yaw_enu_rad that lays the skids (body x) along the estimated wind;
  // nullopt while the lean is too small to tell the wind's direction.
  std::optional<double> skid_yaw_enu_rad(double yaw_enu_rad) const;
  bool paused() const { return paused_; }
  // the low-passed horizontal thrust direction (ENU, length sin(lean)): points upwind
  const Eigen::Vector2d& lean_enu() const { return lean_enu_; }

 private:
  TouchdownGateConfig config_;
  double last_s_ = -1.0;
  Eigen::Vector2d lean_enu_ = Eigen::Vector2d::Zero();
  bool paused_ = false;
  double calm_since_s_ = -1.0;
  double paused_total_s_ = 0.0;
};

}  // namespace uavsim::missions::mbzirc2020
