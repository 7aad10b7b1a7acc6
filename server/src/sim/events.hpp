// Simulation events (crash, landed, balloon popped, failure, ...), stamped with sim time. The sim socket
// API streams them; tests and scoring read them.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace uavsim::server::sim {

enum class EventType {
  kCrash,           // hard impact or vehicle-vehicle contact: the vehicle is dead
  kTakeoff,         // left the ground (truth)
  kTouchdown,       // back on the ground (truth)
  kArmed,
  kDisarmed,
  kModeChange,
  kVehicleKilled,   // fault injection
  kMotorFailure,    // fault injection
  kBalloonPopped,
  kLandedOnTarget,
  kStateFault,      // a vehicle's force or state went non-finite or ran away: killed and put back, once
};
const char* event_type_name(EventType type);

struct Event {
  uint64_t seq = 0;      // 0, 1, 2, ... in the order recorded
  double time_s = 0.0;   // sim time
  EventType type = EventType::kCrash;
  int vehicle = -1;      // -1 when not about a vehicle
  std::string detail;
};

// An append-only log: readers keep their own cursor (next seq), so several subscribers can follow it.
class EventLog {
 public:
  const Event& add(double time_s, EventType type, int vehicle, std::string detail);
  const std::vector<Event>& all() const { return events_; }
  // Events with seq >= from_seq.
  std::vector<Event> since(uint64_t from_seq) const;
  size_t count(EventType type) const;
  void clear() { events_.clear(); }

 private:
  std::vector<Event> events_;
};

}  // namespace uavsim::server::sim
