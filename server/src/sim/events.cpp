#include "sim/events.hpp"

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
  // the oldest event makes room once the log is full
  if (events_.size() == kCapacity) events_.pop_front();
  Event e;
  e.seq = next_seq_++;
  e.time_s = time_s;
  e.type = type;
  e.vehicle = vehicle;
  e.detail = std::move(detail);
  ++counts_[static_cast<size_t>(type)];
  events_.push_back(std::move(e));
  return events_.back();
}

std::vector<Event> EventLog::since(uint64_t from_seq) const {
  if (from_seq >= next_seq_) return {};
  const uint64_t skip = from_seq > first_seq() ? from_seq - first_seq() : 0;
  return std::vector<Event>(events_.begin() + static_cast<long>(skip), events_.end());
}

void EventLog::clear() {
  events_.clear();
  next_seq_ = 0;
  counts_ = {};
}

}  // namespace uavsim::server::sim
