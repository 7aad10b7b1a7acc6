// GuidedSetpoints on a fake link: each kind of target sets only its fields (the type mask) in the
// local NED or global frame.
#include "guided_setpoints.hpp"

#include <gtest/gtest.h>

#include "fake_mav_port.hpp"
#include "uavsim/common/mavlink/generated/enums.hpp"

namespace uavsim::client {
namespace {

namespace mav = common::mavlink;
namespace msg = common::mavlink::msg;
using mav::to_underlying;
using testing::FakeMavPort;

// a resend period longer than any test: only the first send is seen
constexpr double kResendS = 100.0;

class GuidedSetpointsTest : public ::testing::Test {
 protected:
  std::unique_ptr<EventLoop> loop_ = testing::make_loop();
  FakeMavPort port_{*loop_};
  GuidedSetpoints setpoints_{*loop_, port_, kResendS};
};

TEST_F(GuidedSetpointsTest, APositionWithYawSetsPositionAndYawOnly) {
  ASSERT_TRUE(setpoints_.position_ned({1, 2, -3}, 0.5));
  const auto sp = port_.sent<msg::SetPositionTargetLocalNed>();
  ASSERT_EQ(sp.size(), 1u);
  EXPECT_EQ(sp[0].coordinate_frame, to_underlying(mav::MavFrame::LocalNed));
  EXPECT_EQ(sp[0].type_mask, 2552);  // velocity, acceleration and yaw rate ignored
  EXPECT_EQ(sp[0].z, -3.0f);
  EXPECT_EQ(sp[0].yaw, 0.5f);
  ASSERT_TRUE(setpoints_.position_ned({1, 2, -3}, std::nullopt));
  EXPECT_EQ(port_.sent<msg::SetPositionTargetLocalNed>().back().type_mask, 3576);  // and yaw
}

TEST_F(GuidedSetpointsTest, VelocityTargetsCarryAYawRateOrAYaw) {
  ASSERT_TRUE(setpoints_.velocity_ned({1, 0, 0}, std::nullopt, -0.2));
  auto sp = port_.sent<msg::SetPositionTargetLocalNed>().back();
  EXPECT_EQ(sp.type_mask, 1479);  // position, acceleration and yaw ignored
  EXPECT_EQ(sp.vx, 1.0f);
  EXPECT_EQ(sp.yaw_rate, -0.2f);
  ASSERT_TRUE(setpoints_.velocity_ned({1, 0, 0}, 1.0, std::nullopt));
  EXPECT_EQ(port_.sent<msg::SetPositionTargetLocalNed>().back().type_mask, 2503);
  setpoints_.cancel();
}

TEST_F(GuidedSetpointsTest, AGlobalTargetIsAmslInDegreesE7) {
  ASSERT_TRUE(setpoints_.position_global({47.397742, 8.545594, 500.0}, std::nullopt));
  const auto sp = port_.sent<msg::SetPositionTargetGlobalInt>();
  ASSERT_EQ(sp.size(), 1u);
  EXPECT_EQ(sp[0].coordinate_frame, to_underlying(mav::MavFrame::GlobalInt));
  EXPECT_EQ(sp[0].lat_int, 473977420);
  EXPECT_EQ(sp[0].alt, 500.0f);
}

TEST_F(GuidedSetpointsTest, ALostLinkIsReported) {
  port_.open = false;
  EXPECT_EQ(setpoints_.position_ned({0, 0, 0}, std::nullopt).code(), Error::kConnectionLost);
}

}  // namespace
}  // namespace uavsim::client
