// TelemetryDecoder: the Vehicle's telemetry cache. It asks the vehicle for its telemetry streams on
// connect (and for HOME_POSITION until it has one), and decodes what arrives into Telemetry through
// a table of message id => handler, one small function a message. STATUSTEXT is kept apart (the
// last 100 texts and a callback).
//
// Library internal; loop thread only.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "mav_port.hpp"
#include "uavsim/client/event_loop.hpp"
#include "uavsim/client/vehicle.hpp"
#include "uavsim/common/mavlink/generated/messages.hpp"

namespace uavsim::client {

class TelemetryDecoder {
 public:
  // Handles the telemetry messages on port; loop gives the heartbeat's arrival time.
  TelemetryDecoder(EventLoop& loop, MavPort& port);
  ~TelemetryDecoder();
  TelemetryDecoder(const TelemetryDecoder&) = delete;
  TelemetryDecoder& operator=(const TelemetryDecoder&) = delete;

  // A new connection: nothing known yet.
  void reset() { tm_ = Telemetry{}; }
  // Asks for the streams at rate_hz (position and attitude; status groups slower), the messages no
  // stream carries by interval, and HOME_POSITION every second until it arrives.
  void request_streams(double rate_hz);
  // Stops asking for HOME_POSITION (the link closed).
  void stop();

  Telemetry& telemetry() { return tm_; }
  const Telemetry& telemetry() const { return tm_; }
  const std::vector<std::string>& status_texts() const { return texts_; }
  // changed: after every decoded message but STATUSTEXT; status: after every STATUSTEXT.
  void on_changed(std::function<void()> fn) { changed_ = std::move(fn); }
  void on_status_text(std::function<void(int, const std::string&)> fn) { status_ = std::move(fn); }

 private:
  // routes message Msg to a member that applies it to the cache, then reports the change
  template <class Msg>
  void route(void (TelemetryDecoder::*apply)(const Msg&));

  void apply(const common::mavlink::msg::Heartbeat& m);
  void apply(const common::mavlink::msg::SysStatus& m);
  void apply(const common::mavlink::msg::GpsRawInt& m);
  void apply(const common::mavlink::msg::LocalPositionNed& m);
  void apply(const common::mavlink::msg::GlobalPositionInt& m);
  void apply(const common::mavlink::msg::Attitude& m);
  void apply(const common::mavlink::msg::BatteryStatus& m);
  void apply(const common::mavlink::msg::ExtendedSysState& m);
  void apply(const common::mavlink::msg::EkfStatusReport& m);
  void apply(const common::mavlink::msg::HomePosition& m);
  void apply(const common::mavlink::msg::GpsGlobalOrigin& m);
  void apply(const common::mavlink::msg::MountStatus& m);
  void apply(const common::mavlink::msg::GimbalDeviceAttitudeStatus& m);
  void apply(const common::mavlink::msg::MissionCurrent& m);
  void apply(const common::mavlink::msg::MissionItemReached& m);
  void add_status_text(const common::mavlink::msg::Statustext& m);

  EventLoop& loop_;
  MavPort& port_;
  Telemetry tm_;
  std::vector<std::string> texts_;
  std::function<void()> changed_;
  std::function<void(int, const std::string&)> status_;
  TimerId home_timer_ = 0;
};

}  // namespace uavsim::client
