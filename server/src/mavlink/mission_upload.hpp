// One client's mission upload as a state machine (docs/mavlink.md §6.2): MISSION_COUNT opens it,
// each MISSION_ITEM[_INT] in sequence is taken and the next one requested, the last one hands the
// mission to the flight controller; an unanswered request is repeated after 1 s of sim time, the
// upload is cancelled after 8 s without an item. Pure: events in (with sim time), steps out; the
// link sends what a step asks for and reads each item (MAVLink -> fc::MissionItem) when the machine
// takes it.
#pragma once

#include <cstdint>
#include <optional>
#include <variant>
#include <vector>

#include "fc/fc_types.hpp"

namespace uavsim::server::mavlink {

// What the link does after an event, in this order: hand over the mission, request an item, ack.
struct UploadStep {
  std::optional<std::vector<fc::MissionItem>> mission;  // complete (or cleared): set this mission
  std::optional<int> request_seq;                       // send MISSION_REQUEST[_INT] for this item
  std::optional<std::uint8_t> ack;    // send MISSION_ACK with this MAV_MISSION_RESULT
  std::uint8_t ack_mission_type = 0;  // the ack's mission_type
  bool rejected = false;              // count a rejected input
};

class MissionUpload {
 public:
  // an item as read, or the MAV_MISSION_RESULT that refuses it
  using ReadItem = std::variant<fc::MissionItem, std::uint8_t>;

  static constexpr int kMaxItems = 700;  // ArduPilot's SITL storage holds ~700 items
  static constexpr double kRequestRetryS = 1.0;
  static constexpr double kTimeoutS = 8.0;

  bool active() const { return active_; }

  // MISSION_COUNT: opens an upload (an empty one clears the mission at once).
  UploadStep on_count(int count, int mission_type, double now_s);
  // MISSION_ITEM[_INT] number seq (not a guided goto): read(seq) is called only for the item
  // expected next.
  template <class Read>
  UploadStep on_item(int seq, int mission_type, double now_s, Read&& read) {
    UploadStep step;
    if (!active_ || mission_type != kMissionTypeMission) {
      step.rejected = true;
      return step;
    }
    if (seq < next_seq_)
      return step;  // a repeat of an item we already have: the next request follows
    if (seq > next_seq_) {
      step.rejected = true;
      step.ack = kInvalidSequence;
      reset();
      return step;
    }
    last_activity_s_ = now_s;
    ReadItem item = read(seq);
    if (const auto* error = std::get_if<std::uint8_t>(&item)) {
      step.ack = *error;
      reset();
      return step;
    }
    return take(std::move(std::get<fc::MissionItem>(item)), now_s);
  }
  // An item whose numbers could not be read: MISSION_ACK ERROR, ending an upload in progress.
  UploadStep on_unreadable_item();
  // Each control step: repeats an unanswered request, cancels a silent upload.
  UploadStep on_tick(double now_s);

 private:
  static constexpr int kMissionTypeMission = 0;
  static const std::uint8_t kInvalidSequence;
  UploadStep take(fc::MissionItem item, double now_s);
  UploadStep request(double now_s);
  void reset() { *this = MissionUpload{}; }

  bool active_ = false;
  int count_ = 0;
  int next_seq_ = 0;
  double last_activity_s_ = 0.0;
  double last_request_s_ = 0.0;
  std::vector<fc::MissionItem> items_;
};

}  // namespace uavsim::server::mavlink
