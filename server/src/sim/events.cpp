#include "sim/events.hpp"

#include <algorithm>

namespace uavsim::server::sim {

const char* event_type_name(EventType type) {
  switch (type) {
    case EventType::kCrash: return "crash";
    case EventType::kTakeoff: return "takeoff";
    case EventType::kTouchdown: return "touchdown";
    case EventType::kArmed: return "armed";
    case EventType::kDisarmed: return "disarmed";
    case EventType::kModeChange: return "mode_change";
    case EventType::kVehicleKilled: return "vehicle_killed";
    case EventType::kMotorFailure: return "motor_failure";
    case EventType::kBalloonPopped: return "balloon_popped";
    case EventType::kLandedOnTarget: return "landed_on_target";
    case EventType::kStateFault: return "state_fault";
  }
  return "unknown";
}

const Event& EventLog::add(double time_s, EventType type, int vehicle, std::string detail) {
  Event e;
  e.seq = events_.size();
  e.time_s = time_s;
  e.type = type;
  e.vehicle = vehicle;
  e.detail = std::move(detail);
  events_.push_back(std::move(e));
  return events_.back();
}

std::vector<Event> EventLog::since(uint64_t from_seq) const {
  if (from_seq >= events_.size()) return {};
  return std::vector<Event>(events_.begin() + static_cast<long>(from_seq), events_.end());
}

size_t EventLog::count(EventType type) const {
  return static_cast<size_t>(std::count_if(events_.begin(), events_.end(),
                                           [type](const Event& e) { return e.type == type; }));
}

}  // namespace uavsim::server::sim
