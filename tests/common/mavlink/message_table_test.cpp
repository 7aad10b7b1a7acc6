#include "uavsim/common/mavlink/generated/message_table.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <set>
#include <sstream>
#include <string>

#include "test_util.hpp"
#include "uavsim/common/mavlink/generated/enum_names.hpp"
#include "uavsim/common/mavlink/generated/enums.hpp"
#include "uavsim/common/mavlink/generated/messages.hpp"

namespace uavsim::common::mavlink {
namespace {

// tests/data/mavlink/all_messages.csv (id,name,crc_extra,min_len,max_len) is the reference list of
// the dialect
TEST(MessageTable, MatchesEveryRowOfTheReferenceCsv) {
  std::ifstream in(test::data_path("all_messages.csv"));
  ASSERT_TRUE(in);
  std::string line;
  std::getline(in, line);  // header
  std::size_t rows = 0;
  while (std::getline(in, line)) {
    if (line.empty()) continue;
    std::istringstream ls(line);
    std::string id, name, crc, min_len, max_len;
    std::getline(ls, id, ',');
    std::getline(ls, name, ',');
    std::getline(ls, crc, ',');
    std::getline(ls, min_len, ',');
    std::getline(ls, max_len, ',');
    const MessageInfo* info = find_message_info(static_cast<std::uint32_t>(std::stoul(id)));
    ASSERT_NE(info, nullptr) << line;
    EXPECT_EQ(info->name, name);
    EXPECT_EQ(info->crc_extra, std::stoi(crc)) << name;
    EXPECT_EQ(info->min_len, std::stoi(min_len)) << name;
    EXPECT_EQ(info->max_len, std::stoi(max_len)) << name;
    ++rows;
  }
  EXPECT_EQ(rows, 325u);
  EXPECT_EQ(all_message_infos().size(), rows);
  EXPECT_EQ(kMessageCount, rows);
}

TEST(MessageTable, UnknownIdsAreNotFound) {
  EXPECT_EQ(find_message_info(3), nullptr);
  EXPECT_EQ(find_message_info(0xFFFFFF), nullptr);
}

TEST(MessageTable, GeneratedStructsAgreeWithTheTable) {
  std::size_t count = 0;
  std::apply(
      [&](auto... m) {
        (
            [&] {
              using M = decltype(m);
              const MessageInfo* info = find_message_info(M::kId);
              ASSERT_NE(info, nullptr) << M::kName;
              EXPECT_STREQ(info->name, M::kName);
              EXPECT_EQ(info->crc_extra, M::kCrcExtra) << M::kName;
              EXPECT_EQ(info->min_len, M::kMinLen) << M::kName;
              EXPECT_EQ(info->max_len, M::kMaxLen) << M::kName;
              ++count;
            }(),
            ...);
      },
      msg::AllMessages{});
  // every message the project speaks (common/generator/messages.txt: the endpoint's and the
  // client's, docs/mavlink.md) has a struct
  EXPECT_GE(count, 67u);
}

TEST(MessageTable, WireOrderSortsBaseFieldsBySizeAndKeepsExtensionsLast) {
  // COMMAND_ACK: command (uint16) and result (uint8) are base fields; progress, result_param2
  // (int32), target_system, target_component are extensions in XML order, not sorted: offsets 3, 4,
  // 8, 9
  msg::CommandAck ack;
  ack.command = 0x0190;
  ack.result = 0x11;
  ack.progress = 0x22;
  ack.result_param2 = 0x33445566;
  ack.target_system = 0x77;
  ack.target_component = 0x88;
  std::array<std::uint8_t, msg::CommandAck::kMaxLen> p{};
  ack.encode(p.data());
  const std::array<std::uint8_t, 10> expected = {0x90, 0x01, 0x11, 0x22, 0x66,
                                                 0x55, 0x44, 0x33, 0x77, 0x88};
  EXPECT_EQ(p, expected);
}

TEST(Enums, ValuesMatchTheDialect) {
  // spot checks against the dialect's definitions (MAVLink's common.xml and ardupilotmega.xml)
  EXPECT_EQ(to_underlying(MavCmd::ComponentArmDisarm), 400u);
  EXPECT_EQ(to_underlying(MavCmd::NavTakeoff), 22u);
  EXPECT_EQ(to_underlying(MavCmd::DoSendBanner), 42428u);
  EXPECT_EQ(to_underlying(MavResult::Accepted), 0u);
  EXPECT_EQ(to_underlying(MavResult::NotInControl), 10u);
  EXPECT_EQ(to_underlying(MavFrame::GlobalRelativeAltInt), 6u);
  EXPECT_EQ(to_underlying(MavModeFlag::SafetyArmed), 128u);
  EXPECT_EQ(to_underlying(MavModeFlag::CustomModeEnabled), 1u);
  EXPECT_EQ(to_underlying(MavState::Standby), 3u);
  EXPECT_EQ(to_underlying(MavType::Hexarotor), 13u);
  EXPECT_EQ(to_underlying(MavAutopilot::Ardupilotmega), 3u);
  EXPECT_EQ(to_underlying(MavSeverity::Info), 6u);
  EXPECT_EQ(to_underlying(MavMissionResult::InvalidSequence), 13u);
  EXPECT_EQ(to_underlying(MavParamType::Real32), 9u);
  EXPECT_EQ(to_underlying(PositionTargetTypemask::YawRateIgnore), 2048u);
  EXPECT_EQ(to_underlying(CopterMode::Guided), 4u);
  EXPECT_EQ(to_underlying(MavSysStatusSensor::Sensor3dGyro), 1u);
}

TEST(EnumNames, AreTheDialectsEntryNamesWithoutTheEnumPrefix) {
  EXPECT_EQ(enum_name(MavCmd::NavTakeoff), "NAV_TAKEOFF");
  EXPECT_EQ(enum_name(MavCmd::ComponentArmDisarm), "COMPONENT_ARM_DISARM");
  EXPECT_EQ(enum_name(MavResult::TemporarilyRejected), "TEMPORARILY_REJECTED");
  // MAV_MISSION_RESULT's entries are MAV_MISSION_*: the common words go
  EXPECT_EQ(enum_name(MavMissionResult::OperationCancelled), "OPERATION_CANCELLED");
  EXPECT_EQ(enum_name(CopterMode::GuidedNogps), "GUIDED_NOGPS");
  EXPECT_EQ(enum_name(MavModeFlag::SafetyArmed), "SAFETY_ARMED");
  // a number that is no entry has no name
  EXPECT_EQ(enum_name(static_cast<MavCmd>(65000)), "");
  EXPECT_EQ(enum_name(static_cast<CopterMode>(8)), "");
}

}  // namespace
}  // namespace uavsim::common::mavlink
