// The telemetry schedule alone: default rates, SET_MESSAGE_INTERVAL, REQUEST_DATA_STREAM, counted
// over sim time at the 500 Hz control step.
#include "mavlink/telemetry_schedule.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <map>

#include "uavsim/common/mavlink/generated/messages.hpp"

namespace uavsim::server::mavlink {
namespace {

namespace msg = ::uavsim::common::mavlink::msg;
constexpr double kStepS = 0.002;  // 500 Hz

// how often each message is sent in (from_s, to_s], one take_due per control step
std::map<std::uint32_t, int> run(TelemetrySchedule& s, double from_s, double to_s) {
  std::map<std::uint32_t, int> sent;
  const int first = static_cast<int>(std::lround(from_s / kStepS)) + 1;
  const int last = static_cast<int>(std::lround(to_s / kStepS));
  for (int k = first; k <= last; ++k) s.take_due(k * kStepS, [&](std::uint32_t id) { ++sent[id]; });
  return sent;
}

TEST(TelemetrySchedule, DefaultRatesAreArduCoptersGroupRates) {
  TelemetrySchedule s(0.0);
  auto sent = run(s, 0.0, 10.0);
  // 10 s: HEARTBEAT 1 Hz = 10, ATTITUDE (EXTRA1, 4 Hz) = 40, SYS_STATUS (EXTENDED_STATUS, 2 Hz) =
  // 20
  EXPECT_EQ(sent[msg::Heartbeat::kId], 10);
  EXPECT_EQ(sent[msg::Attitude::kId], 40);
  EXPECT_EQ(sent[msg::SysStatus::kId], 20);
  EXPECT_EQ(sent.count(msg::AttitudeQuaternion::kId), 0u);  // only when asked
  EXPECT_EQ(s.interval_us(msg::Attitude::kId), 250000);
  EXPECT_EQ(s.interval_us(msg::AttitudeQuaternion::kId), -1);
  EXPECT_EQ(s.interval_us(msg::CommandAck::kId), 0);  // not a stream
}

TEST(TelemetrySchedule, SetMessageIntervalStartsAtOnceStopsAndRestoresTheDefault) {
  TelemetrySchedule s(0.0);
  ASSERT_TRUE(s.set_interval(msg::AttitudeQuaternion::kId, 100000.0, 0.0));  // 10 Hz from now
  auto sent = run(s, 0.0, 1.0);
  // the first at the next step (0.002 s), then on the phase of t = 0: 0.1, 0.2, ..., 1.0 s: 1 + 10
  // = 11
  EXPECT_EQ(sent[msg::AttitudeQuaternion::kId], 11);
  ASSERT_TRUE(s.set_interval(msg::Attitude::kId, -1.0, 1.0));  // stop
  EXPECT_EQ(s.interval_us(msg::Attitude::kId), -1);
  EXPECT_EQ(run(s, 1.0, 2.0).count(msg::Attitude::kId), 0u);
  ASSERT_TRUE(s.set_interval(msg::Attitude::kId, 0.0, 2.0));  // back to 4 Hz
  EXPECT_EQ(s.interval_us(msg::Attitude::kId), 250000);
  // no default to go back to, or no stream at all: FAILED
  EXPECT_FALSE(s.set_interval(msg::AttitudeQuaternion::kId, 0.0, 2.0));
  EXPECT_FALSE(s.set_interval(msg::CommandAck::kId, 100000.0, 2.0));
  // 1 us is clamped to 1 ms
  ASSERT_TRUE(s.set_interval(msg::VfrHud::kId, 1.0, 2.0));
  EXPECT_EQ(s.interval_us(msg::VfrHud::kId), 1000);
}

TEST(TelemetrySchedule, DataStreamGroupsSetTheirMessagesOnly) {
  TelemetrySchedule s(0.0);
  s.set_group_rate(to_underlying(::uavsim::common::mavlink::MavDataStream::Extra1), 10.0, true,
                   0.0);
  auto sent = run(s, 0.0, 2.0);
  EXPECT_EQ(sent[msg::Attitude::kId], 20);  // 10 Hz
  EXPECT_EQ(sent[msg::VfrHud::kId], 8);     // EXTRA2 still 4 Hz
  s.set_group_rate(0, 0.0, false, 2.0);     // all off
  sent = run(s, 2.0, 4.0);
  EXPECT_EQ(sent.count(msg::Attitude::kId), 0u);
  EXPECT_EQ(sent[msg::Heartbeat::kId], 2);  // not in a group: keeps streaming
}

TEST(TelemetrySchedule, ALongGapRestartsTheStreamInsteadOfBursting) {
  TelemetrySchedule s(0.0);
  int heartbeats = 0;
  s.take_due(5.0, [&](std::uint32_t id) { heartbeats += id == msg::Heartbeat::kId; });
  EXPECT_EQ(heartbeats, 1);  // one, not five
  s.take_due(5.5, [&](std::uint32_t id) { heartbeats += id == msg::Heartbeat::kId; });
  EXPECT_EQ(heartbeats, 1);  // next one due at 6 s
  s.take_due(6.0, [&](std::uint32_t id) { heartbeats += id == msg::Heartbeat::kId; });
  EXPECT_EQ(heartbeats, 2);
}

}  // namespace
}  // namespace uavsim::server::mavlink
