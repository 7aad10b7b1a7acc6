// TelemetryDecoder against a fake link: each streamed message lands in its part of the cache with
// ArduCopter's units and flags, STATUSTEXT is kept apart, and connecting asks for the streams.
#include "telemetry_decoder.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <limits>

#include "fake_mav_port.hpp"
#include "uavsim/common/angles.hpp"
#include "uavsim/common/mavlink/generated/enums.hpp"
#include "uavsim/common/mavlink/wire.hpp"

namespace uavsim::client {
namespace {

namespace mav = common::mavlink;
namespace msg = common::mavlink::msg;
using mav::to_underlying;
using testing::FakeMavPort;

constexpr double kTol = 1e-9;
constexpr double kFloatAngleTol_rad = 1e-6;  // the attitude quaternion travels as floats

class TelemetryDecoderTest : public ::testing::Test {
 protected:
  TelemetryDecoderTest() {
    decoder_.on_changed([this] { ++changes_; });
  }
  const Telemetry& tm() const { return decoder_.telemetry(); }

  std::unique_ptr<EventLoop> loop_ = testing::make_loop();
  FakeMavPort port_{*loop_};
  TelemetryDecoder decoder_{*loop_, port_};
  int changes_ = 0;
};

TEST_F(TelemetryDecoderTest, HeartbeatGivesModeArmedAndTheVehicle) {
  port_.sysid = 7;
  msg::Heartbeat hb;
  hb.custom_mode = to_underlying(mav::CopterMode::Guided);
  hb.base_mode = static_cast<std::uint8_t>(to_underlying(mav::MavModeFlag::SafetyArmed) |
                                           to_underlying(mav::MavModeFlag::CustomModeEnabled));
  hb.system_status = to_underlying(mav::MavState::Active);
  port_.deliver(hb);
  EXPECT_TRUE(tm().heartbeat_seen);
  EXPECT_EQ(tm().sysid, 7);
  EXPECT_EQ(tm().mode, FlightMode::kGuided);
  EXPECT_EQ(tm().custom_mode, 4u);
  EXPECT_TRUE(tm().armed);
  EXPECT_EQ(tm().system_status, to_underlying(mav::MavState::Active));
  EXPECT_EQ(changes_, 1);

  hb.base_mode = static_cast<std::uint8_t>(to_underlying(mav::MavModeFlag::CustomModeEnabled));
  port_.deliver(hb);
  EXPECT_FALSE(tm().armed);
  EXPECT_EQ(changes_, 2);
}

TEST_F(TelemetryDecoderTest, PositionsAreScaledAndTheLocalOneAlsoInEnu) {
  msg::GlobalPositionInt g;
  g.lat = 473977420;  // 1e-7 degrees
  g.lon = 85455940;
  g.alt = 498500;          // mm AMSL
  g.relative_alt = 10500;  // mm
  g.hdg = 9000;            // cdeg
  port_.deliver(g);
  EXPECT_TRUE(tm().has_global_position);
  EXPECT_NEAR(tm().position.lat_deg, 47.397742, kTol);
  EXPECT_NEAR(tm().position.lon_deg, 8.545594, kTol);
  EXPECT_NEAR(tm().position.alt_m, 498.5, kTol);
  EXPECT_NEAR(tm().relative_alt_m, 10.5, kTol);
  EXPECT_NEAR(tm().heading_deg, 90.0, kTol);
  g.hdg = 65535;  // unknown: the heading is kept
  port_.deliver(g);
  EXPECT_NEAR(tm().heading_deg, 90.0, kTol);

  msg::LocalPositionNed l;
  l.time_boot_ms = 1500;
  l.x = 1, l.y = 2, l.z = -3;  // north, east, down
  l.vx = 0.5f, l.vy = -1, l.vz = 0.25f;
  port_.deliver(l);
  EXPECT_NEAR(tm().vehicle_time_s, 1.5, kTol);
  // ENU = (east, north, up)
  EXPECT_EQ(tm().position_enu_m, Eigen::Vector3d(2, 1, 3));
  EXPECT_EQ(tm().velocity_enu_m_s, Eigen::Vector3d(-1, 0.5, -0.25));
  EXPECT_EQ(changes_, 3);
}

TEST_F(TelemetryDecoderTest, PrearmBitBatteryAndEkfHorizontalPosition) {
  msg::SysStatus s;
  s.onboard_control_sensors_health = to_underlying(mav::MavSysStatusSensor::PrearmCheck);
  s.voltage_battery = 12600;  // mV
  s.current_battery = 1250;   // cA
  s.battery_remaining = 87;
  port_.deliver(s);
  EXPECT_TRUE(tm().prearm_ok);
  EXPECT_NEAR(tm().battery_voltage_v, 12.6, kTol);
  EXPECT_NEAR(tm().battery_current_a, 12.5, kTol);
  EXPECT_EQ(tm().battery_remaining_pct, 87);

  msg::EkfStatusReport e;
  e.flags = static_cast<std::uint16_t>(to_underlying(mav::EkfStatusFlags::Attitude));
  port_.deliver(e);
  EXPECT_FALSE(tm().ekf_ok);  // attitude alone is no position
  e.flags = static_cast<std::uint16_t>(to_underlying(mav::EkfStatusFlags::PredPosHorizAbs));
  port_.deliver(e);
  EXPECT_TRUE(tm().ekf_ok);
}

TEST_F(TelemetryDecoderTest, HomeOriginGimbalAndMissionProgress) {
  msg::HomePosition h;
  h.latitude = 473977420, h.longitude = 85455940, h.altitude = 488000;
  h.x = 1, h.y = 2, h.z = 3;
  port_.deliver(h);
  EXPECT_TRUE(tm().home_set);
  EXPECT_NEAR(tm().home.alt_m, 488.0, kTol);
  EXPECT_EQ(tm().home_ned_m, Eigen::Vector3d(1, 2, 3));

  msg::MountStatus m;
  m.pointing_a = -4500;  // cdeg
  port_.deliver(m);
  EXPECT_TRUE(tm().has_gimbal);
  EXPECT_NEAR(tm().gimbal_pitch_deg, -45.0, kTol);

  msg::MissionItemReached r;
  r.seq = 3;
  port_.deliver(r);
  EXPECT_EQ(tm().mission_last_reached, 3);
}

// GIMBAL_DEVICE_ATTITUDE_STATUS: the camera 6 deg up, 10 deg right of the heading, 2 deg rolled, in
// the vehicle frame; the same camera on a vehicle heading 30 deg reported in the earth frame
TEST_F(TelemetryDecoderTest, GimbalDeviceAttitudeInTheVehicleFrame) {
  using common::kDegToRad;
  const Eigen::Quaterniond q_vehicle = Eigen::AngleAxisd(10 * kDegToRad, Eigen::Vector3d::UnitZ()) *
                                       Eigen::AngleAxisd(6 * kDegToRad, Eigen::Vector3d::UnitY()) *
                                       Eigen::AngleAxisd(2 * kDegToRad, Eigen::Vector3d::UnitX());
  const auto status = [](const Eigen::Quaterniond& q, std::uint16_t flags, float delta_yaw) {
    msg::GimbalDeviceAttitudeStatus m;
    m.time_boot_ms = 61234;
    m.q = {static_cast<float>(q.w()), static_cast<float>(q.x()), static_cast<float>(q.y()),
           static_cast<float>(q.z())};
    m.flags = flags;
    m.delta_yaw = delta_yaw;
    return m;
  };
  const auto expect_camera = [&] {
    EXPECT_TRUE(tm().has_gimbal_attitude);
    EXPECT_NEAR(tm().gimbal_attitude_time_s, 61.234, kTol);
    EXPECT_NEAR(tm().gimbal_attitude_roll_rad, 2 * kDegToRad, kFloatAngleTol_rad);
    EXPECT_NEAR(tm().gimbal_attitude_pitch_rad, 6 * kDegToRad, kFloatAngleTol_rad);
    EXPECT_NEAR(tm().gimbal_attitude_yaw_rad, 10 * kDegToRad, kFloatAngleTol_rad);
  };
  port_.deliver(status(q_vehicle, 4 | 8 | 32,
                       30 * kDegToRad));  // ROLL_LOCK | PITCH_LOCK | YAW_IN_VEHICLE_FRAME
  expect_camera();
  decoder_.reset();
  const Eigen::Quaterniond q_earth =
      Eigen::AngleAxisd(30 * kDegToRad, Eigen::Vector3d::UnitZ()) * q_vehicle;
  port_.deliver(
      status(q_earth, 4 | 8 | 16 | 64, 30 * kDegToRad));  // ... | YAW_LOCK | YAW_IN_EARTH_FRAME
  expect_camera();
  // an earth-frame report without the heading cannot be turned back: ignored
  decoder_.reset();
  port_.deliver(status(q_earth, 4 | 8 | 16 | 64, std::numeric_limits<float>::quiet_NaN()));
  EXPECT_FALSE(tm().has_gimbal_attitude);
}

TEST_F(TelemetryDecoderTest, StatusTextsKeepTheLastHundredAndAreNoTelemetryChange) {
  std::vector<std::string> heard;
  decoder_.on_status_text([&](int severity, const std::string& text) {
    EXPECT_EQ(severity, to_underlying(mav::MavSeverity::Info));
    heard.push_back(text);
  });
  for (int i = 0; i <= 100; ++i) {
    msg::Statustext t;
    t.severity = to_underlying(mav::MavSeverity::Info);
    mav::set_string(t.text, "text " + std::to_string(i));
    port_.deliver(t);
  }
  EXPECT_EQ(heard.size(), 101u);
  ASSERT_EQ(decoder_.status_texts().size(), 100u);
  EXPECT_EQ(decoder_.status_texts().front(), "text 1");
  EXPECT_EQ(decoder_.status_texts().back(), "text 100");
  EXPECT_EQ(changes_, 0);
}

TEST_F(TelemetryDecoderTest, ResetForgetsEverything) {
  port_.deliver(msg::Heartbeat{});
  ASSERT_TRUE(tm().heartbeat_seen);
  decoder_.reset();
  EXPECT_FALSE(tm().heartbeat_seen);
}

TEST_F(TelemetryDecoderTest, ConnectingAsksForTheStreamGroupsAndTheUnstreamedMessages) {
  decoder_.request_streams(20.0);
  const auto streams = port_.sent<msg::RequestDataStream>();
  ASSERT_EQ(streams.size(), 5u);
  for (const auto& s : streams) {
    EXPECT_EQ(s.start_stop, 1);
    if (s.req_stream_id == to_underlying(mav::MavDataStream::Position)) {
      EXPECT_EQ(s.req_message_rate, 20);
    }
  }
  const auto intervals = port_.sent<msg::CommandLong>();
  ASSERT_EQ(intervals.size(), 4u);
  for (const auto& c : intervals)
    EXPECT_EQ(c.command, to_underlying(mav::MavCmd::SetMessageInterval));
  EXPECT_EQ(intervals[0].param1, static_cast<float>(msg::HomePosition::kId));
  EXPECT_EQ(intervals[0].param2, 1e6f);  // once a second, in microseconds
  decoder_.stop();
}

}  // namespace
}  // namespace uavsim::client
