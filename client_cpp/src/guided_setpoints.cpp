// GUIDED targets: which fields a target sets is its type mask (everything else ignored); the time
// stamp is the loop clock.
#include "guided_setpoints.hpp"

#include <algorithm>
#include <initializer_list>

#include "mav_units.hpp"
#include "uavsim/common/mavlink/generated/enums.hpp"

namespace uavsim::client {

namespace mav = common::mavlink;
namespace msg = common::mavlink::msg;
using mav::to_underlying;

namespace {

// SET_POSITION_TARGET type masks: what a setpoint sets, everything else ignored
constexpr std::uint16_t ignore(std::initializer_list<mav::PositionTargetTypemask> bits) {
  std::uint16_t m = 0;
  for (auto b : bits) m = static_cast<std::uint16_t>(m | to_underlying(b));
  return m;
}
using Ignore = mav::PositionTargetTypemask;
constexpr std::uint16_t kIgnoreVel = ignore({Ignore::VxIgnore, Ignore::VyIgnore, Ignore::VzIgnore});
constexpr std::uint16_t kIgnorePos = ignore({Ignore::XIgnore, Ignore::YIgnore, Ignore::ZIgnore});
constexpr std::uint16_t kIgnoreAcc = ignore({Ignore::AxIgnore, Ignore::AyIgnore, Ignore::AzIgnore});
constexpr std::uint16_t kIgnoreYaw = ignore({Ignore::YawIgnore});
constexpr std::uint16_t kIgnoreYawRate = ignore({Ignore::YawRateIgnore});
constexpr std::uint16_t kMaskPos = kIgnoreVel | kIgnoreAcc | kIgnoreYaw | kIgnoreYawRate;  // 3576
constexpr std::uint16_t kMaskPosYaw = kIgnoreVel | kIgnoreAcc | kIgnoreYawRate;            // 2552
constexpr std::uint16_t kMaskVel = kIgnorePos | kIgnoreAcc | kIgnoreYaw | kIgnoreYawRate;  // 3527
constexpr std::uint16_t kMaskVelYaw = kIgnorePos | kIgnoreAcc | kIgnoreYawRate;            // 2503
constexpr std::uint16_t kMaskVelYawRate = kIgnorePos | kIgnoreAcc | kIgnoreYaw;            // 1479
static_assert(kMaskPos == 3576 && kMaskPosYaw == 2552 && kMaskVel == 3527 && kMaskVelYaw == 2503 &&
              kMaskVelYawRate == 1479);

std::uint32_t time_boot_ms(const EventLoop& loop) {
  return static_cast<std::uint32_t>(std::max(0.0, loop.now()) * 1000.0);
}

Result<void> link_lost() { return Result<void>::fail(Error::kConnectionLost, "the link was lost"); }

}  // namespace

GuidedSetpoints::GuidedSetpoints(EventLoop& loop, MavPort& port, double resend_s)
    : loop_(loop), port_(port), resend_s_(resend_s) {}

Result<void> GuidedSetpoints::position_ned(const Eigen::Vector3d& ned_m,
                                           std::optional<double> yaw_ned_rad) {
  auto sp = local(yaw_ned_rad ? kMaskPosYaw : kMaskPos);
  sp.x = static_cast<float>(ned_m.x());
  sp.y = static_cast<float>(ned_m.y());
  sp.z = static_cast<float>(ned_m.z());
  if (yaw_ned_rad) sp.yaw = static_cast<float>(*yaw_ned_rad);
  return send_local(sp, false);
}

Result<void> GuidedSetpoints::position_global(const Geodetic& p,
                                              std::optional<double> yaw_ned_rad) {
  cancel();
  msg::SetPositionTargetGlobalInt sp;
  sp.target_system = port_.target_sysid();
  sp.target_component = port_.target_compid();
  sp.coordinate_frame = to_underlying(mav::MavFrame::GlobalInt);  // altitude AMSL
  sp.type_mask = yaw_ned_rad ? kMaskPosYaw : kMaskPos;
  sp.lat_int = deg_e7(p.lat_deg);
  sp.lon_int = deg_e7(p.lon_deg);
  sp.alt = static_cast<float>(p.alt_m);
  if (yaw_ned_rad) sp.yaw = static_cast<float>(*yaw_ned_rad);
  sp.time_boot_ms = time_boot_ms(loop_);
  if (!port_.send(sp)) return link_lost();
  return {};
}

Result<void> GuidedSetpoints::velocity_ned(const Eigen::Vector3d& v,
                                           std::optional<double> yaw_ned_rad,
                                           std::optional<double> yaw_rate_ned_rad_s) {
  auto sp = local(yaw_ned_rad ? kMaskVelYaw : yaw_rate_ned_rad_s ? kMaskVelYawRate : kMaskVel);
  sp.vx = static_cast<float>(v.x());
  sp.vy = static_cast<float>(v.y());
  sp.vz = static_cast<float>(v.z());
  if (yaw_ned_rad) sp.yaw = static_cast<float>(*yaw_ned_rad);
  if (yaw_rate_ned_rad_s) sp.yaw_rate = static_cast<float>(*yaw_rate_ned_rad_s);
  return send_local(sp, true);
}

void GuidedSetpoints::cancel() {
  if (resend_timer_ != 0) loop_.cancel(resend_timer_);
  resend_timer_ = 0;
  resend_.reset();
}

msg::SetPositionTargetLocalNed GuidedSetpoints::local(std::uint16_t type_mask) const {
  msg::SetPositionTargetLocalNed sp;
  sp.target_system = port_.target_sysid();
  sp.target_component = port_.target_compid();
  sp.coordinate_frame = to_underlying(mav::MavFrame::LocalNed);
  sp.type_mask = type_mask;
  sp.time_boot_ms = time_boot_ms(loop_);
  return sp;
}

Result<void> GuidedSetpoints::send_local(const msg::SetPositionTargetLocalNed& sp, bool resend) {
  cancel();
  if (!port_.send(sp)) return link_lost();
  if (resend) {
    resend_ = sp;
    resend_timer_ = loop_.call_every(resend_s_, [this] {
      if (resend_) port_.send(*resend_);
    });
  }
  return {};
}

}  // namespace uavsim::client
