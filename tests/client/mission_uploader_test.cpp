// MissionUploader against a scripted vehicle on a fake link: each request answered in its own form
// (MISSION_ITEM_INT or the legacy MISSION_ITEM), home as item 0, and the MISSION_ACK's verdict.
#include "mission_uploader.hpp"

#include <gtest/gtest.h>

#include "fake_mav_port.hpp"
#include "uavsim/common/mavlink/generated/enums.hpp"

namespace uavsim::client {
namespace {

namespace mav = common::mavlink;
namespace msg = common::mavlink::msg;
using mav::MavMissionResult;
using mav::to_underlying;
using testing::as;
using testing::FakeMavPort;

constexpr double kTimeoutS = 5.0;
const Geodetic kHome{47.397742, 8.545594, 488.0};

msg::MissionAck mission_ack(MavMissionResult r) {
  msg::MissionAck a;
  a.type = static_cast<std::uint8_t>(to_underlying(r));
  return a;
}

class MissionUploaderTest : public ::testing::Test {
 protected:
  std::unique_ptr<EventLoop> loop_ = testing::make_loop();
  FakeMavPort port_{*loop_};
  MissionUploader uploader_{*loop_, port_};
};

TEST_F(MissionUploaderTest, EachRequestIsAnsweredInItsOwnFormAndTheAckAcceptsIt) {
  // the vehicle asks for item 0 and 2 with MISSION_REQUEST_INT and item 1 with the legacy request
  port_.vehicle = [this](const FakeMavPort::Sent& s) {
    const auto request = [this](std::uint16_t seq) {
      msg::MissionRequestInt r;
      r.seq = seq;
      if (seq == 1) {
        msg::MissionRequest legacy;
        legacy.seq = seq;
        port_.reply(legacy);
      } else {
        port_.reply(r);
      }
    };
    if (auto c = as<msg::MissionCount>(s)) request(0);
    if (auto i = as<msg::MissionItemInt>(s)) {
      if (i->seq == 0) request(1);
      if (i->seq == 2) port_.reply(mission_ack(MavMissionResult::Accepted));
    }
    if (auto i = as<msg::MissionItem>(s)) request(2);
  };
  auto r = uploader_.upload({MissionItem::takeoff(10.0), MissionItem::waypoint(47.4, 8.55, 12.0)},
                            kHome, kTimeoutS);
  ASSERT_TRUE(r) << r.message();
  const auto counts = port_.sent<msg::MissionCount>();
  ASSERT_EQ(counts.size(), 1u);
  EXPECT_EQ(counts[0].count, 3);  // home + 2
  const auto items = port_.sent<msg::MissionItemInt>();
  ASSERT_EQ(items.size(), 2u);
  // item 0: home, absolute altitude
  EXPECT_EQ(items[0].frame, to_underlying(mav::MavFrame::Global));
  EXPECT_EQ(items[0].x, 473977420);
  EXPECT_EQ(items[0].z, 488.0f);
  EXPECT_EQ(items[1].seq, 2);
  EXPECT_EQ(items[1].command, to_underlying(mav::MavCmd::NavWaypoint));
  EXPECT_EQ(items[1].y, 85500000);
  const auto legacy = port_.sent<msg::MissionItem>();
  ASSERT_EQ(legacy.size(), 1u);
  EXPECT_EQ(legacy[0].command, to_underlying(mav::MavCmd::NavTakeoff));
  EXPECT_EQ(legacy[0].z, 10.0f);
}

TEST_F(MissionUploaderTest, ARefusalCarriesTheMissionResult) {
  port_.vehicle = [this](const FakeMavPort::Sent& s) {
    if (as<msg::MissionCount>(s)) port_.reply(mission_ack(MavMissionResult::NoSpace));
  };
  auto r = uploader_.upload({MissionItem::land()}, kHome, kTimeoutS);
  ASSERT_FALSE(r);
  EXPECT_EQ(r.code(), Error::kDenied);
  EXPECT_EQ(r.error().mav_result, 4);
  EXPECT_EQ(r.message(), "mission upload refused: MAV_MISSION_NO_SPACE (4)");

  port_.vehicle = [this](const FakeMavPort::Sent& s) {
    if (as<msg::MissionCount>(s)) port_.reply(mission_ack(MavMissionResult::OperationCancelled));
  };
  EXPECT_EQ(uploader_.upload({MissionItem::land()}, kHome, kTimeoutS).code(), Error::kCancelled);
}

TEST_F(MissionUploaderTest, ASilentVehicleIsATimeout) {
  auto r = uploader_.upload({MissionItem::land()}, kHome, 0.05);
  ASSERT_FALSE(r);
  EXPECT_EQ(r.code(), Error::kTimeout);
  EXPECT_EQ(r.message(), "mission upload: the vehicle never requested an item");
}

TEST_F(MissionUploaderTest, RequestsOutsideAnUploadAreNotAnswered) {
  msg::MissionRequestInt r;
  r.seq = 0;
  port_.deliver(r);
  EXPECT_EQ(port_.sent_count(), 0u);
}

TEST_F(MissionUploaderTest, ALostLinkEndsTheUpload) {
  port_.vehicle = [this](const FakeMavPort::Sent& s) {
    if (as<msg::MissionCount>(s)) {
      loop_->post([this] {
        port_.open = false;
        uploader_.abort();
      });
    }
  };
  auto r = uploader_.upload({MissionItem::land()}, kHome, kTimeoutS);
  EXPECT_EQ(r.code(), Error::kConnectionLost);
}

TEST_F(MissionUploaderTest, NothingToUploadOrNoLinkFailsAtOnce) {
  EXPECT_EQ(uploader_.upload({}, kHome, kTimeoutS).code(), Error::kInvalidArgument);
  port_.open = false;
  EXPECT_EQ(uploader_.upload({MissionItem::land()}, kHome, kTimeoutS).code(), Error::kNotConnected);
  EXPECT_EQ(port_.sent_count(), 0u);
}

}  // namespace
}  // namespace uavsim::client
