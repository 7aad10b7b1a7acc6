// Simulation events (crash, landed, balloon popped, failure, ...), stamped with sim time. The sim socket
// API streams them; tests and scoring read them.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <deque>
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

// The log of one run (since the last reset): readers keep their own cursor (the next seq they want), so
// several subscribers can follow it. It holds only the latest kCapacity events, so that a long run with
// many vehicles and flights keeps a bounded log (and bounded `events from_seq 0` replies); seq numbers and
// per-type counts go on across what was dropped.
class EventLog {
 public:
  static constexpr size_t kCapacity = 4096;

  const Event& add(double time_s, EventType type, int vehicle, std::string detail);
  // The events still held, oldest first: seq first_seq() .. next_seq() - 1.
  const std::deque<Event>& recent() const { return events_; }
  // The seq of the oldest event still held (next_seq() when none is).
  uint64_t first_seq() const { return next_seq_ - events_.size(); }
  // The seq the next event will get: the number of events recorded since the last clear.
  uint64_t next_seq() const { return next_seq_; }
  // Events still held with seq >= from_seq (those before first_seq() are gone).
  std::vector<Event> since(uint64_t from_seq) const;
  // Events of this type recorded since the last clear, dropped ones included.
  size_t count(EventType type) const { return counts_[static_cast<size_t>(type)]; }
  void clear();

 private:
  std::deque<Event> events_;
  uint64_t next_seq_ = 0;
  std::array<size_t, static_cast<size_t>(EventType::kStateFault) + 1> counts_{};
};

}  // namespace uavsim::server::sim
