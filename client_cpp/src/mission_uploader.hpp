// MissionUploader: the mission upload protocol (MAVLink mission microservice) as ArduPilot speaks
// it. MISSION_COUNT goes out (re-sent while the vehicle stays silent), the vehicle requests each
// item (MISSION_REQUEST_INT, or the legacy MISSION_REQUEST, answered in its own form) and ends with
// MISSION_ACK. Item 0 is home, as ArduPilot expects (it overwrites it with the real home).
//
// Library internal; loop thread only.
#pragma once

#include <optional>
#include <vector>

#include "mav_port.hpp"
#include "uavsim/client/event_loop.hpp"
#include "uavsim/client/geodesy.hpp"
#include "uavsim/client/result.hpp"
#include "uavsim/client/vehicle.hpp"
#include "uavsim/common/mavlink/generated/messages.hpp"

namespace uavsim::client {

class MissionUploader {
 public:
  // Handles MISSION_REQUEST_INT, MISSION_REQUEST and MISSION_ACK on port.
  MissionUploader(EventLoop& loop, MavPort& port);
  MissionUploader(const MissionUploader&) = delete;
  MissionUploader& operator=(const MissionUploader&) = delete;

  // Uploads home (item 0) and items, waiting on the loop at most timeout_s. kNotConnected,
  // kInvalidArgument (no items), kDenied / kCancelled with the MAV_MISSION_RESULT when the vehicle
  // refuses it, kTimeout, kConnectionLost.
  Result<void> upload(const std::vector<MissionItem>& items, const Geodetic& home,
                      double timeout_s);
  // Stops answering requests (the link closed).
  void abort() { active_ = false; }

 private:
  void on_request(const common::mavlink::Frame& f);
  void on_ack(const common::mavlink::Frame& f);
  Result<void> outcome(double timeout_s) const;

  EventLoop& loop_;
  MavPort& port_;
  bool active_ = false;
  std::vector<common::mavlink::msg::MissionItemInt> items_;
  std::optional<int> ack_;
  int requests_ = 0;
};

}  // namespace uavsim::client
