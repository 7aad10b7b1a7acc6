#include "mavlink/telemetry_schedule.hpp"

#include <algorithm>
#include <iterator>

#include "uavsim/common/mavlink/generated/messages.hpp"

namespace uavsim::server::mavlink {

namespace msg = ::uavsim::common::mavlink::msg;

namespace {

struct StreamDef {
  std::uint32_t msgid;
  StreamGroup group;
};

constexpr StreamDef kStreamable[] = {
    {msg::Heartbeat::kId, StreamGroup::kNone},
    {msg::SysStatus::kId, StreamGroup::kExtendedStatus},
    {msg::GpsRawInt::kId, StreamGroup::kExtendedStatus},
    {msg::MissionCurrent::kId, StreamGroup::kExtendedStatus},
    {msg::PositionTargetLocalNed::kId, StreamGroup::kExtendedStatus},
    {msg::GlobalPositionInt::kId, StreamGroup::kPosition},
    {msg::LocalPositionNed::kId, StreamGroup::kPosition},
    {msg::Attitude::kId, StreamGroup::kExtra1},
    {msg::VfrHud::kId, StreamGroup::kExtra2},
    {msg::SystemTime::kId, StreamGroup::kExtra3},
    {msg::BatteryStatus::kId, StreamGroup::kExtra3},
    {msg::EkfStatusReport::kId, StreamGroup::kExtra3},
    // ArduCopter streams GIMBAL_DEVICE_ATTITUDE_STATUS in EXTRA3; MOUNT_ORIENTATION (deprecated)
    // rides along for clients that still read it (e.g. DroneKit's gimbal attribute)
    {msg::MountOrientation::kId, StreamGroup::kExtra3},
    {msg::GimbalDeviceAttitudeStatus::kId, StreamGroup::kExtra3},
    {msg::AttitudeQuaternion::kId, StreamGroup::kNone},
    {msg::HomePosition::kId, StreamGroup::kNone},
    {msg::ExtendedSysState::kId, StreamGroup::kNone},
    {msg::MountStatus::kId, StreamGroup::kNone},
    {msg::GpsGlobalOrigin::kId, StreamGroup::kNone},
};

double default_group_rate_hz(StreamGroup g) {
  switch (g) {
    case StreamGroup::kExtendedStatus:
      return 2.0;
    case StreamGroup::kPosition:
      return 4.0;
    case StreamGroup::kExtra1:
      return 4.0;
    case StreamGroup::kExtra2:
      return 4.0;
    case StreamGroup::kExtra3:
      return 2.0;
    case StreamGroup::kNone:
      return 0.0;
  }
  return 0.0;
}

// HEARTBEAT at 1 Hz, a group's message at its group's rate, the rest off until asked for
double default_interval_s(const StreamDef& d) {
  if (d.msgid == msg::Heartbeat::kId) return 1.0;
  const double hz = default_group_rate_hz(d.group);
  return hz > 0 ? 1.0 / hz : 0.0;
}

}  // namespace

TelemetrySchedule::TelemetrySchedule(double now_s) {
  streams_.reserve(std::size(kStreamable));
  for (const StreamDef& d : kStreamable) {
    Stream s;
    s.msgid = d.msgid;
    s.group = d.group;
    s.default_interval_s = default_interval_s(d);
    s.interval_s = s.default_interval_s;
    s.next_due_s = now_s + s.interval_s;
    streams_.push_back(s);
  }
}

bool TelemetrySchedule::streamable(std::uint32_t msgid) {
  return std::any_of(std::begin(kStreamable), std::end(kStreamable),
                     [msgid](const StreamDef& d) { return d.msgid == msgid; });
}

TelemetrySchedule::Stream* TelemetrySchedule::find(std::uint32_t msgid) {
  Stream* found = nullptr;
  for (Stream& s : streams_) {
    if (s.msgid == msgid) found = &s;
  }
  return found;
}

bool TelemetrySchedule::set_interval(std::uint32_t msgid, double interval_us, double now_s) {
  Stream* stream = find(msgid);
  if (stream == nullptr) return false;
  double interval_s = 0.0;
  if (interval_us == 0.0) {
    if (stream->default_interval_s <= 0.0) return false;
    interval_s = stream->default_interval_s;
  } else if (interval_us < 0.0) {
    interval_s = 0.0;
  } else {
    interval_s = std::clamp(interval_us * 1e-6, 1e-3, 60.0);
  }
  stream->interval_s = interval_s;
  stream->next_due_s = now_s;  // first one at the next control step
  return true;
}

std::int32_t TelemetrySchedule::interval_us(std::uint32_t msgid) const {
  std::int32_t us = 0;  // not available
  for (const Stream& s : streams_) {
    if (s.msgid == msgid)
      us = s.interval_s > 0 ? static_cast<std::int32_t>(s.interval_s * 1e6) : -1;
  }
  return us;
}

void TelemetrySchedule::set_group_rate(int group, double rate_hz, bool start, double now_s) {
  for (Stream& s : streams_) {
    if (s.group == StreamGroup::kNone) continue;
    if (group != 0 && static_cast<int>(s.group) != group) continue;
    s.interval_s = (start && rate_hz > 0) ? 1.0 / rate_hz : 0.0;
    s.next_due_s = now_s + s.interval_s;
  }
}

}  // namespace uavsim::server::mavlink
