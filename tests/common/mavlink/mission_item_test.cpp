#include "uavsim/common/mavlink/mission_item.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>

#include "uavsim/common/mavlink/generated/enums.hpp"

namespace uavsim::common::mavlink {
namespace {

std::uint8_t frame_id(MavFrame f) { return static_cast<std::uint8_t>(to_underlying(f)); }

msg::MissionItem legacy_waypoint(float lat_deg, float lon_deg, MavFrame frame) {
  msg::MissionItem m;
  m.param1 = 2.5f;  // hold time
  m.param2 = 0.5f;
  m.param3 = -1.0f;
  m.param4 = 90.0f;
  m.x = lat_deg;
  m.y = lon_deg;
  m.z = 12.25f;
  m.seq = 7;
  m.command = static_cast<std::uint16_t>(to_underlying(MavCmd::NavWaypoint));
  m.target_system = 3;
  m.target_component = 190;
  m.frame = frame_id(frame);
  m.current = 0;
  m.autocontinue = 1;
  m.mission_type = 0;
  return m;
}

// 47.5 and -122.25 are exact in a float: the 1e7 scaling gives whole numbers, with nothing to round
TEST(MissionItem, LegacyToIntScalesDegreesBy1e7AndMapsTheFloatFrames) {
  const auto i =
      mission_item_int_from_legacy(legacy_waypoint(47.5f, -122.25f, MavFrame::GlobalRelativeAlt));
  ASSERT_TRUE(i.has_value());
  EXPECT_EQ(i->x, 475000000);
  EXPECT_EQ(i->y, -1222500000);
  EXPECT_EQ(i->frame, frame_id(MavFrame::GlobalRelativeAltInt));
  EXPECT_EQ(i->z, 12.25f);
  EXPECT_EQ(i->param1, 2.5f);
  EXPECT_EQ(i->param2, 0.5f);
  EXPECT_EQ(i->param3, -1.0f);
  EXPECT_EQ(i->param4, 90.0f);
  EXPECT_EQ(i->seq, 7);
  EXPECT_EQ(i->command, to_underlying(MavCmd::NavWaypoint));
  EXPECT_EQ(i->target_system, 3);
  EXPECT_EQ(i->target_component, 190);
  EXPECT_EQ(i->autocontinue, 1);
  EXPECT_EQ(mission_item_int_from_legacy(legacy_waypoint(47.5f, 8.0f, MavFrame::Global))->frame,
            frame_id(MavFrame::GlobalInt));
  // a frame without an _INT twin (terrain has one of its own, but it is kept as sent) is copied
  EXPECT_EQ(
      mission_item_int_from_legacy(legacy_waypoint(47.5f, 8.0f, MavFrame::GlobalTerrainAlt))->frame,
      frame_id(MavFrame::GlobalTerrainAlt));
}

TEST(MissionItem, LegacyToIntRefusesWhatTheInt32FieldsCannotHold) {
  // the poles and the antimeridian are still positions: 90e7 and 180e7 fit an int32 (max
  // 2147483647)
  const auto edge = mission_item_int_from_legacy(legacy_waypoint(-90.0f, 180.0f, MavFrame::Global));
  ASSERT_TRUE(edge.has_value());
  EXPECT_EQ(edge->x, -900000000);
  EXPECT_EQ(edge->y, 1800000000);
  EXPECT_FALSE(mission_item_int_from_legacy(legacy_waypoint(90.5f, 0.0f, MavFrame::Global)));
  EXPECT_FALSE(mission_item_int_from_legacy(legacy_waypoint(0.0f, -180.5f, MavFrame::Global)));
  // 300 degrees * 1e7 = 3e9 would not fit: refused, not wrapped
  EXPECT_FALSE(mission_item_int_from_legacy(legacy_waypoint(0.0f, 300.0f, MavFrame::Global)));
  const float nan = std::numeric_limits<float>::quiet_NaN();
  EXPECT_FALSE(mission_item_int_from_legacy(legacy_waypoint(nan, 0.0f, MavFrame::Global)));
  EXPECT_FALSE(mission_item_int_from_legacy(
      legacy_waypoint(0.0f, std::numeric_limits<float>::infinity(), MavFrame::Global)));
}

TEST(MissionItem, IntToLegacyAndBackIsTheIdentityUpToTheFloatResolution) {
  msg::MissionItemInt i =
      *mission_item_int_from_legacy(legacy_waypoint(47.5f, -122.25f, MavFrame::Global));
  i.x = 473977419;  // 47.3977419 deg: not a float
  i.y = 85455939;   // 8.5455939 deg
  const msg::MissionItem legacy = legacy_mission_item(i);
  EXPECT_EQ(legacy.frame, frame_id(MavFrame::Global));
  EXPECT_EQ(legacy.seq, 7);
  EXPECT_EQ(legacy.param1, 2.5f);
  EXPECT_EQ(legacy.z, 12.25f);
  const auto back = mission_item_int_from_legacy(legacy);
  ASSERT_TRUE(back.has_value());
  EXPECT_EQ(back->frame, frame_id(MavFrame::GlobalInt));
  // a float near 47 has a 2^(5-23) deg = 3.8e-6 deg step: rounding to it moves a latitude by at
  // most half of that, 1.9e-6 deg = 19 units of 1e-7 deg; near 8.5 the step is 2^(3-23) deg, half
  // of it 4.8 units
  EXPECT_LE(std::abs(back->x - i.x), 19);
  EXPECT_LE(std::abs(back->y - i.y), 5);
  EXPECT_EQ(back->seq, i.seq);
  EXPECT_EQ(back->command, i.command);
  EXPECT_EQ(back->param4, i.param4);
}

}  // namespace
}  // namespace uavsim::common::mavlink
