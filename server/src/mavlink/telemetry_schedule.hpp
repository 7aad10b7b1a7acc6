// Which messages a client has streamed, and when each is next due (sim time). One schedule per
// client: every streamable message starts at its default interval (ArduCopter's REQUEST_DATA_STREAM
// group rates, telemetry.cpp), SET_MESSAGE_INTERVAL and REQUEST_DATA_STREAM change it. Pure: no
// sockets, no clock; the link asks for the due messages at each control step and sends them.
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include "uavsim/common/mavlink/generated/enums.hpp"

namespace uavsim::server::mavlink {

// A message a client may have streamed, with the data-stream group REQUEST_DATA_STREAM addresses it
// by.
enum class StreamGroup : std::uint8_t {
  kNone = 0,  // only by SET_MESSAGE_INTERVAL
  kExtendedStatus = common::mavlink::to_underlying(common::mavlink::MavDataStream::ExtendedStatus),
  kPosition = common::mavlink::to_underlying(common::mavlink::MavDataStream::Position),
  kExtra1 = common::mavlink::to_underlying(common::mavlink::MavDataStream::Extra1),
  kExtra2 = common::mavlink::to_underlying(common::mavlink::MavDataStream::Extra2),
  kExtra3 = common::mavlink::to_underlying(common::mavlink::MavDataStream::Extra3),
};

class TelemetrySchedule {
 public:
  // Every streamable message at its default interval, the first of each due one interval after
  // now_s.
  explicit TelemetrySchedule(double now_s);

  // Whether msgid is one of the streamable messages. Thread-safe (pure).
  static bool streamable(std::uint32_t msgid);

  // Calls send(msgid) for each stream due at t, in table order, and schedules its next one: the
  // phase is kept, but after a long gap (or a rate change) the stream restarts from t instead of
  // bursting.
  template <class F>
  void take_due(double t, F&& send) {
    constexpr double kEps = 1e-9;
    for (Stream& s : streams_) {
      if (s.interval_s <= 0.0 || t + kEps < s.next_due_s) continue;
      send(s.msgid);
      s.next_due_s += s.interval_s;
      if (s.next_due_s + kEps < t) s.next_due_s = t + s.interval_s;
    }
  }

  // SET_MESSAGE_INTERVAL: interval_us 0 = the default, < 0 = stop, else clamped to [1 ms, 60 s];
  // the first one is due at now_s. False (MAV_RESULT_FAILED): not streamable, or no default to
  // return to.
  bool set_interval(std::uint32_t msgid, double interval_us, double now_s);
  // MESSAGE_INTERVAL's interval_us: the current interval, -1 when off, 0 when msgid is not
  // streamable.
  std::int32_t interval_us(std::uint32_t msgid) const;
  // REQUEST_DATA_STREAM: group 0 (ALL) or one group to rate_hz, or off (start false or rate 0); the
  // first one is due an interval after now_s.
  void set_group_rate(int group, double rate_hz, bool start, double now_s);

 private:
  struct Stream {
    std::uint32_t msgid = 0;
    StreamGroup group = StreamGroup::kNone;
    double default_interval_s = 0.0;  // 0 = not streamed unless asked
    double interval_s = 0.0;          // current; 0 = off
    double next_due_s = 0.0;
  };
  Stream* find(std::uint32_t msgid);
  std::vector<Stream> streams_;
};

}  // namespace uavsim::server::mavlink
