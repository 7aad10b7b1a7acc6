// What a launcher tells the video's viewer that the server cannot see (docs/protocol.md "Video
// overlay"): mission counters (coverage-run's "coverage 62.0 %") and notes (mbzirc2020-run's "uav0
// takes over the side of uav1"), burnt into the --record video's overlay beside the server's own
// counters and events. Without --record they are kept and shown nowhere. Never read by the
// simulation: they change no sim outcome.
//
// Ops: overlay_counter {"name", "text"} sets (empty text: removes) a counter line; overlay_note
// {"text", "vehicle"?} adds an event line at the current sim time, in the vehicle's colour if one
// is named.
#pragma once

#include <cstdint>
#include <deque>
#include <map>
#include <string>
#include <vector>

#include "api/op_table.hpp"
#include "sim/simulation.hpp"

namespace uavsim::server::api {

inline constexpr size_t kMaxOverlayCounters = 8;
inline constexpr size_t kMaxOverlayNotes = 16;      // the newest are kept
inline constexpr size_t kMaxOverlayTextBytes = 80;  // printable ASCII
inline constexpr size_t kMaxOverlayNameBytes = 32;

struct OverlayNote {
  double time_s = 0.0;
  int vehicle = -1;
  std::string text;
};

class OverlayOps : public OpGroup {
 public:
  // sim must outlive this object. Before the loop.
  explicit OverlayOps(const sim::Simulation& sim) : sim_(sim) {}

  // overlay_counter, overlay_note.
  void register_ops(OpTable& table) override;

  // The counters' texts in name order. Loop thread only.
  std::vector<std::string> counters() const;
  // The notes kept, oldest first. Loop thread only.
  const std::deque<OverlayNote>& notes() const { return notes_; }

 private:
  // the ops (loop thread)
  void counter(const Json& request, OpReply* reply);
  void note(const Json& request, OpReply* reply);

  const sim::Simulation& sim_;
  std::map<std::string, std::string> counters_;
  std::deque<OverlayNote> notes_;
};

}  // namespace uavsim::server::api
