// The mission upload state machine alone: items in sequence, repeats, gaps, bad items, retries and
// the timeout, all in sim time.
#include "mavlink/mission_upload.hpp"

#include <gtest/gtest.h>

#include "uavsim/common/mavlink/generated/enums.hpp"

namespace uavsim::server::mavlink {
namespace {

using ::uavsim::common::mavlink::MavMissionResult;
using ::uavsim::common::mavlink::to_underlying;

constexpr std::uint8_t code(MavMissionResult r) {
  return static_cast<std::uint8_t>(to_underlying(r));
}
constexpr int kMission = 0, kFence = 1;

// an item read as a waypoint whose x is its sequence number
MissionUpload::ReadItem waypoint(int seq) {
  fc::MissionItem item;
  item.position_enu_m.x() = seq;
  return item;
}

TEST(MissionUpload, RequestsEachItemInTurnAndHandsOverTheMission) {
  MissionUpload u;
  UploadStep s = u.on_count(3, kMission, 0.0);
  EXPECT_EQ(s.request_seq, 0);
  EXPECT_TRUE(u.active());
  s = u.on_item(0, kMission, 0.1, waypoint);
  EXPECT_EQ(s.request_seq, 1);
  EXPECT_FALSE(s.ack.has_value());
  s = u.on_item(1, kMission, 0.2, waypoint);
  EXPECT_EQ(s.request_seq, 2);
  s = u.on_item(2, kMission, 0.3, waypoint);
  EXPECT_FALSE(s.request_seq.has_value());
  EXPECT_EQ(s.ack, code(MavMissionResult::Accepted));
  ASSERT_TRUE(s.mission.has_value());
  ASSERT_EQ(s.mission->size(), 3u);
  EXPECT_EQ(s.mission->at(2).position_enu_m.x(), 2.0);
  EXPECT_FALSE(u.active());
}

TEST(MissionUpload, EmptyCountClearsAndTooManyOrAFenceIsRefused) {
  MissionUpload u;
  UploadStep s = u.on_count(0, kMission, 0.0);
  ASSERT_TRUE(s.mission.has_value());
  EXPECT_TRUE(s.mission->empty());
  EXPECT_EQ(s.ack, code(MavMissionResult::Accepted));
  EXPECT_EQ(u.on_count(MissionUpload::kMaxItems + 1, kMission, 0.0).ack,
            code(MavMissionResult::NoSpace));
  s = u.on_count(2, kFence, 0.0);
  EXPECT_EQ(s.ack, code(MavMissionResult::Unsupported));
  EXPECT_EQ(s.ack_mission_type, kFence);
  EXPECT_FALSE(u.active());
}

TEST(MissionUpload, RepeatsAreIgnoredAGapEndsTheUpload) {
  MissionUpload u;
  u.on_count(3, kMission, 0.0);
  u.on_item(0, kMission, 0.1, waypoint);
  int reads = 0;
  const auto counting = [&](int seq) {
    ++reads;
    return waypoint(seq);
  };
  // a repeat of item 0: nothing to do, nothing read
  UploadStep s = u.on_item(0, kMission, 0.2, counting);
  EXPECT_FALSE(s.ack || s.request_seq || s.rejected);
  EXPECT_EQ(reads, 0);
  // item 2 before item 1: INVALID_SEQUENCE, the upload is over
  s = u.on_item(2, kMission, 0.3, counting);
  EXPECT_EQ(s.ack, code(MavMissionResult::InvalidSequence));
  EXPECT_TRUE(s.rejected);
  EXPECT_EQ(reads, 0);
  EXPECT_FALSE(u.active());
  // an item with no upload open is a rejected input, unanswered
  s = u.on_item(1, kMission, 0.4, counting);
  EXPECT_TRUE(s.rejected);
  EXPECT_FALSE(s.ack.has_value());
}

TEST(MissionUpload, AnItemThatCannotBeReadEndsTheUploadWithItsError) {
  MissionUpload u;
  u.on_count(2, kMission, 0.0);
  u.on_item(0, kMission, 0.1, waypoint);
  const UploadStep s = u.on_item(1, kMission, 0.2, [](int) -> MissionUpload::ReadItem {
    return code(MavMissionResult::UnsupportedFrame);
  });
  EXPECT_EQ(s.ack, code(MavMissionResult::UnsupportedFrame));
  EXPECT_FALSE(s.mission.has_value());
  EXPECT_FALSE(u.active());
  u.on_count(2, kMission, 1.0);
  EXPECT_EQ(u.on_unreadable_item().ack, code(MavMissionResult::Error));
  EXPECT_FALSE(u.active());
}

TEST(MissionUpload, RepeatsTheRequestEverySecondAndGivesUpAfterEight) {
  MissionUpload u;
  u.on_count(2, kMission, 10.0);
  EXPECT_FALSE(u.on_tick(10.5).request_seq.has_value());
  EXPECT_EQ(u.on_tick(11.0).request_seq, 0);  // 1 s after the request
  EXPECT_FALSE(u.on_tick(11.5).request_seq.has_value());
  // an item resets the silence: 8 s counted from it
  u.on_item(0, kMission, 12.0, waypoint);
  EXPECT_FALSE(u.on_tick(20.0).ack.has_value());  // 8.0 s: not beyond
  const UploadStep s = u.on_tick(20.01);
  EXPECT_EQ(s.ack, code(MavMissionResult::OperationCancelled));
  EXPECT_FALSE(u.active());
  EXPECT_FALSE(u.on_tick(30.0).ack.has_value());
}

}  // namespace
}  // namespace uavsim::server::mavlink
