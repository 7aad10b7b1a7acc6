// GuidedSetpoints: position and velocity targets for a vehicle in GUIDED (SET_POSITION_TARGET_*).
// ArduCopter neither acknowledges them nor keeps a velocity target for long (it stops after about
// 3 s), so a velocity target is re-sent every resend period until another target replaces it or
// cancel() ends it.
//
// Library internal; loop thread only.
#pragma once

#include <Eigen/Core>
#include <optional>

#include "mav_port.hpp"
#include "uavsim/client/event_loop.hpp"
#include "uavsim/client/geodesy.hpp"
#include "uavsim/client/result.hpp"
#include "uavsim/common/mavlink/generated/messages.hpp"

namespace uavsim::client {

class GuidedSetpoints {
 public:
  GuidedSetpoints(EventLoop& loop, MavPort& port, double resend_s);
  ~GuidedSetpoints() { cancel(); }
  GuidedSetpoints(const GuidedSetpoints&) = delete;
  GuidedSetpoints& operator=(const GuidedSetpoints&) = delete;

  // Fly to a local NED position (NED yaw, clockwise from north; none: keep the heading).
  Result<void> position_ned(const Eigen::Vector3d& ned_m, std::optional<double> yaw_ned_rad);
  // Fly to a geodetic position, altitude AMSL.
  Result<void> position_global(const Geodetic& point_amsl, std::optional<double> yaw_ned_rad);
  // Fly at a local NED velocity with an absolute NED yaw, a NED yaw rate (clockwise positive), or
  // neither; re-sent until replaced or cancelled.
  Result<void> velocity_ned(const Eigen::Vector3d& v_ned_m_s, std::optional<double> yaw_ned_rad,
                            std::optional<double> yaw_rate_ned_rad_s);
  // Stops re-sending the velocity target.
  void cancel();

 private:
  common::mavlink::msg::SetPositionTargetLocalNed local(std::uint16_t type_mask) const;
  Result<void> send_local(const common::mavlink::msg::SetPositionTargetLocalNed& sp, bool resend);

  EventLoop& loop_;
  MavPort& port_;
  double resend_s_;
  TimerId resend_timer_ = 0;
  std::optional<common::mavlink::msg::SetPositionTargetLocalNed> resend_;
};

}  // namespace uavsim::client
