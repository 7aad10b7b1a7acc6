// The command mapper alone: COMMAND_LONG/INT and SET_MODE read into typed requests (MAVLink's
// conventions converted), the ack results, and the requests carried out on a flight controller on
// the ground.
#include "mavlink/command_mapper.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "../fc/test_airframes.hpp"
#include "uavsim/common/angles.hpp"

namespace uavsim::server::mavlink {
namespace {

using namespace ::uavsim::common::mavlink;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kTol = 1e-12;
constexpr double kLatLonTol_deg = 1e-9;  // a float64 degree read back from its 1e-7 integer
constexpr std::uint8_t kAccepted = to_underlying(MavResult::Accepted);
constexpr std::uint8_t kDenied = to_underlying(MavResult::Denied);
constexpr std::uint8_t kFailed = to_underlying(MavResult::Failed);
constexpr std::uint8_t kUnsupported = to_underlying(MavResult::Unsupported);

CommandArgs command(MavCmd cmd, std::array<double, 7> p = {}) {
  CommandArgs c;
  c.command = static_cast<std::uint16_t>(to_underlying(cmd));
  c.p = p;
  return c;
}

// the flight-controller request a command maps to (fails the test when there is none)
template <class Request>
Request fc_request(const CommandArgs& c) {
  const MappedCommand m = map_command(c);
  EXPECT_TRUE(m.request.has_value()) << "refused with " << int(m.result);
  if (!m.request) return {};
  const auto* fc = std::get_if<FcRequest>(&*m.request);
  EXPECT_NE(fc, nullptr);
  if (fc == nullptr) return {};
  const auto* r = std::get_if<Request>(fc);
  EXPECT_NE(r, nullptr);
  return r ? *r : Request{};
}

// the immediate answer to a command refused as it stands
std::optional<std::uint8_t> refused(const CommandArgs& c) {
  const MappedCommand m = map_command(c);
  if (m.request) return std::nullopt;
  return m.result;
}

TEST(CommandMapper, ArmForcedOnlyByTheMagicValues) {
  EXPECT_FALSE(fc_request<cmd::Arm>(command(MavCmd::ComponentArmDisarm, {1, 0})).force);
  EXPECT_TRUE(fc_request<cmd::Arm>(command(MavCmd::ComponentArmDisarm, {1, 2989})).force);
  EXPECT_TRUE(fc_request<cmd::Arm>(command(MavCmd::ComponentArmDisarm, {1, 21196})).force);
  EXPECT_FALSE(fc_request<cmd::Disarm>(command(MavCmd::ComponentArmDisarm, {0, 2989})).force);
  EXPECT_TRUE(fc_request<cmd::Disarm>(command(MavCmd::ComponentArmDisarm, {0, 21196})).force);
  EXPECT_EQ(refused(command(MavCmd::ComponentArmDisarm, {0.5})), kUnsupported);
}

TEST(CommandMapper, SetModeNeedsTheCustomModeFlagAndAKnownMode) {
  msg::SetMode m;
  m.base_mode = 1;  // MAV_MODE_FLAG_CUSTOM_MODE_ENABLED
  m.custom_mode = 4;
  EXPECT_EQ(fc_request<cmd::SetMode>(command_args(m)).mode, fc::Mode::kGuided);
  EXPECT_EQ(refused(command(MavCmd::DoSetMode, {0, 4})), kFailed);    // no custom-mode flag
  EXPECT_EQ(refused(command(MavCmd::DoSetMode, {1, 1})), kFailed);    // ACRO: not emulated
  EXPECT_EQ(refused(command(MavCmd::DoSetMode, {1, 4.5})), kDenied);  // not an integer
  EXPECT_EQ(refused(command(MavCmd::DoSetMode, {300, 4})), kDenied);  // no uint8
  EXPECT_EQ(fc_request<cmd::SetMode>(command(MavCmd::NavLoiterUnlim)).mode, fc::Mode::kLoiter);
}

TEST(CommandMapper, ConditionYawHeadingBecomesEnuYaw) {
  const double deg = common::kPi / 180.0;
  // absolute: yaw_enu = 90 deg - heading; north (0) = +90 deg ENU, east (90) = 0, west (270) = -180
  EXPECT_NEAR(fc_request<cmd::Yaw>(command(MavCmd::ConditionYaw, {0, 0, 0, 0})).yaw.yaw_enu_rad,
              common::kPi / 2, kTol);
  EXPECT_NEAR(fc_request<cmd::Yaw>(command(MavCmd::ConditionYaw, {90, 0, 0, 0})).yaw.yaw_enu_rad,
              0.0, kTol);
  EXPECT_NEAR(fc_request<cmd::Yaw>(command(MavCmd::ConditionYaw, {270, 0, 0, 0})).yaw.yaw_enu_rad,
              -common::kPi, kTol);
  // relative: clockwise (+1, and 0 = "shortest", which ArduCopter turns clockwise) is a negative
  // ENU change
  const auto cw = fc_request<cmd::Yaw>(command(MavCmd::ConditionYaw, {30, 15, 1, 1})).yaw;
  EXPECT_TRUE(cw.relative);
  EXPECT_NEAR(cw.yaw_enu_rad, -30 * deg, kTol);
  EXPECT_NEAR(cw.rate_rad_s, 15 * deg, kTol);  // 15 deg/s = 0.2618 rad/s
  EXPECT_NEAR(fc_request<cmd::Yaw>(command(MavCmd::ConditionYaw, {30, 0, 0, 1})).yaw.yaw_enu_rad,
              -30 * deg, kTol);
  EXPECT_NEAR(fc_request<cmd::Yaw>(command(MavCmd::ConditionYaw, {30, 0, -1, 1})).yaw.yaw_enu_rad,
              30 * deg, kTol);
  // refused at the edge: an angle beyond a turn, a negative or non-finite rate
  EXPECT_EQ(refused(command(MavCmd::ConditionYaw, {1e30, 0, 0, 0})), kDenied);
  EXPECT_EQ(refused(command(MavCmd::ConditionYaw, {90, -5, 0, 0})), kDenied);
  EXPECT_EQ(refused(command(MavCmd::ConditionYaw, {90, kNaN, 0, 0})), kDenied);
}

TEST(CommandMapper, ChangeSpeedTypeBecomesALimit) {
  EXPECT_EQ(fc_request<cmd::ChangeSpeed>(command(MavCmd::DoChangeSpeed, {0, 5})).limit,
            fc::SpeedLimit::kHorizontal);
  EXPECT_EQ(fc_request<cmd::ChangeSpeed>(command(MavCmd::DoChangeSpeed, {1, 5})).limit,
            fc::SpeedLimit::kHorizontal);
  EXPECT_EQ(fc_request<cmd::ChangeSpeed>(command(MavCmd::DoChangeSpeed, {2, 5})).limit,
            fc::SpeedLimit::kClimb);
  EXPECT_EQ(fc_request<cmd::ChangeSpeed>(command(MavCmd::DoChangeSpeed, {3, 5})).limit,
            fc::SpeedLimit::kDescent);
  EXPECT_DOUBLE_EQ(fc_request<cmd::ChangeSpeed>(command(MavCmd::DoChangeSpeed, {1, 7.5})).speed_m_s,
                   7.5);
  EXPECT_EQ(refused(command(MavCmd::DoChangeSpeed, {4, 5})), kDenied);
  EXPECT_EQ(refused(command(MavCmd::DoChangeSpeed, {1, kNaN})), kDenied);
}

TEST(CommandMapper, TakeoffAsCommandIntMustBeRelativeToHome) {
  EXPECT_DOUBLE_EQ(fc_request<cmd::Takeoff>(command(MavCmd::NavTakeoff, {0, 0, 0, 0, 0, 0, 12}))
                       .altitude_above_home_m,
                   12.0);
  msg::CommandInt m;
  m.command = static_cast<std::uint16_t>(to_underlying(MavCmd::NavTakeoff));
  m.z = 12;
  m.frame = static_cast<std::uint8_t>(to_underlying(MavFrame::Global));
  EXPECT_EQ(refused(command_args(m)), kDenied);
  m.frame = static_cast<std::uint8_t>(to_underlying(MavFrame::GlobalRelativeAltInt));
  EXPECT_DOUBLE_EQ(fc_request<cmd::Takeoff>(command_args(m)).altitude_above_home_m, 12.0);
  EXPECT_EQ(refused(command(MavCmd::NavTakeoff, {0, 0, 0, 0, 0, 0, kNaN})), kDenied);
}

TEST(CommandMapper, RepositionReadsDegE7AndKeepsWhatIsNaN) {
  EXPECT_EQ(refused(command(MavCmd::DoReposition)), kUnsupported);  // COMMAND_INT only
  msg::CommandInt m;
  m.command = static_cast<std::uint16_t>(to_underlying(MavCmd::DoReposition));
  m.frame = static_cast<std::uint8_t>(to_underlying(MavFrame::GlobalInt));
  m.x = 473977420;  // 47.397742 deg
  m.y = 85455940;   // 8.545594 deg
  m.z = 500;
  const auto r = fc_request<cmd::Reposition>(command_args(m));
  ASSERT_TRUE(r.lat_lon.has_value());
  EXPECT_NEAR(r.lat_lon->lat_deg, 47.397742, kLatLonTol_deg);
  EXPECT_NEAR(r.lat_lon->lon_deg, 8.545594, kLatLonTol_deg);
  EXPECT_EQ(r.alt_m, 500.0);
  EXPECT_TRUE(r.amsl);
  // lat/lon 0: stay; NaN altitude: keep
  m.x = m.y = 0;
  m.z = std::numeric_limits<float>::quiet_NaN();
  const auto stay = fc_request<cmd::Reposition>(command_args(m));
  EXPECT_FALSE(stay.lat_lon.has_value());
  EXPECT_FALSE(stay.alt_m.has_value());
  m.x = 950000000;  // 95 deg: no latitude
  EXPECT_EQ(refused(command_args(m)), kDenied);
}

TEST(CommandMapper, MessageIdsAreRangeChecked) {
  EXPECT_EQ(refused(command(MavCmd::RequestMessage, {-1})), kDenied);
  EXPECT_EQ(refused(command(MavCmd::RequestMessage, {16777216})),
            kDenied);  // 2^24: beyond a message id
  const MappedCommand m = map_command(command(MavCmd::RequestMessage, {30}));
  ASSERT_TRUE(m.request.has_value());
  const auto* link = std::get_if<LinkRequest>(&*m.request);
  ASSERT_NE(link, nullptr);
  EXPECT_EQ(std::get<cmd::RequestMessage>(*link).msgid, 30u);
  EXPECT_EQ(refused(command(MavCmd::SetMessageInterval, {30, kNaN})), kDenied);
  EXPECT_EQ(refused(command(MavCmd::RequestAutopilotCapabilities, {0})),
            kAccepted);  // nothing asked
  EXPECT_EQ(refused(command(static_cast<MavCmd>(31000))), kUnsupported);
}

TEST(CommandMapper, ArmDisarmAndTakeoffRefusalsAckFailedOthersOneToOne) {
  // ArduPilot answers a refused arm, disarm or take-off with FAILED
  EXPECT_EQ(ack_result(cmd::Arm{}, fc::CommandResult::kDenied), kFailed);
  EXPECT_EQ(ack_result(cmd::Disarm{}, fc::CommandResult::kInvalid), kFailed);
  EXPECT_EQ(ack_result(cmd::Takeoff{}, fc::CommandResult::kUnsupported), kUnsupported);
  EXPECT_EQ(ack_result(cmd::SetMode{}, fc::CommandResult::kDenied), kDenied);
  EXPECT_EQ(ack_result(cmd::Land{}, fc::CommandResult::kInvalid), kDenied);
  EXPECT_EQ(ack_result(cmd::Yaw{}, fc::CommandResult::kFailed), kFailed);
  EXPECT_EQ(ack_result(cmd::Rtl{}, fc::CommandResult::kAccepted), kAccepted);
}

TEST(CommandMapper, RequestsCarriedOutOnAVehicleOnTheGround) {
  const auto af = fc::test::make_quad();
  fc::FlightController fc(af, 1);
  const common::GeodeticOrigin origin;
  EXPECT_EQ(execute(cmd::Disarm{}, fc, origin), kAccepted);     // already disarmed
  EXPECT_EQ(execute(cmd::Takeoff{10.0}, fc, origin), kFailed);  // disarmed
  EXPECT_EQ(execute(cmd::Yaw{}, fc, origin), kFailed);          // disarmed
  EXPECT_EQ(execute(cmd::ChangeSpeed{fc::SpeedLimit::kClimb, 0.0}, fc, origin),
            kDenied);  // 0 m/s: invalid
  EXPECT_EQ(execute(cmd::SetMode{fc::Mode::kAltHold}, fc, origin), kAccepted);
  EXPECT_EQ(fc.mode(), fc::Mode::kAltHold);
  EXPECT_EQ(execute(cmd::Reposition{}, fc, origin), kFailed);  // GUIDED needs a GPS fix
}

TEST(CommandMapper, GimbalRequestsLeaveWhatIsNotGiven) {
  GimbalState g;
  g.pitch_deg = -10;
  g.mount_mode = 3;
  apply(cmd::MountControl{std::nullopt, 5.0, 20.0, 0}, g, 2.5);
  EXPECT_EQ(g.pitch_deg, -10.0);
  EXPECT_EQ(g.roll_deg, 5.0);
  EXPECT_EQ(g.yaw_deg, 20.0);
  EXPECT_EQ(g.mount_mode, 3);  // 0 keeps the mode
  EXPECT_EQ(g.stamp_s, 2.5);
  apply(cmd::GimbalPitchYaw{-45.0, std::nullopt, 1.0, 2.0, true}, g, 3.0);
  EXPECT_EQ(g.pitch_deg, -45.0);
  EXPECT_EQ(g.yaw_deg, 20.0);
  EXPECT_TRUE(g.yaw_earth_frame);
  EXPECT_EQ(g.mount_mode, to_underlying(MavMountMode::MavlinkTargeting));
}

}  // namespace
}  // namespace uavsim::server::mavlink
