// The overlay network of the flock (the thesis the project descends from, section 3.3): every agent
// keeps an Agents Database (ADB) with the latest known state of every other agent, merges the ADB
// copies its neighbours broadcast (Algorithm 1) and ages its records, evicting those older than the
// age allowed for their hop distance (Algorithm 2). The leader is the lowest id alive, the agent
// itself included. Pure: time enters as elapsed milliseconds.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <vector>

namespace uavsim::missions::coverage {

struct AgentRecord {
  int id = 0;
  uint16_t seq = 0;  // the agent's message counter (wraps)
  double x_m = 0.0;  // ENU position (world frame)
  double y_m = 0.0;
  double heading_rad = 0.0;  // target heading, ENU (counter-clockwise from east)
  double vx_m_s = 0.0;       // ENU velocity (feed-forward for the followers; beyond the thesis)
  double vy_m_s = 0.0;
  int distance_hops = 0;  // 1 = heard directly
  int age_ms = 0;         // age of the information
  bool landed = false;    // the agent had landed (its radio stays on; it cannot lead)
};

// True when sequence number a is newer than b (16-bit serial arithmetic, RFC 1982).
bool seq_newer(uint16_t a, uint16_t b);

class AgentsDatabase {
 public:
  // max_allowed_age_ms(distance_hops) is Algorithm 2's MAX_ALLOWED_AGE.
  AgentsDatabase(int local_id, std::function<int(int)> max_allowed_age_ms);

  int local_id() const { return local_id_; }

  // Algorithm 1: a message from `sender` (its own state) carrying (part of) its ADB. Records about
  // this agent are skipped; the others arrive one hop farther than the sender had them.
  void on_message(const AgentRecord& sender, const std::vector<AgentRecord>& sender_adb);
  // Algorithm 1's MERGE: stores the record if the id is unknown or the record is newer. A record
  // already too old for its distance is not stored, nor, beyond the thesis, an evicted agent's
  // record that is not newer than the one it was evicted with: the farther a copy travels the more
  // age Algorithm 2 allows it, so agents that hear each other passed a silent agent's last record
  // back and forth for ever, a hop farther each time (count to infinity).
  void merge(const AgentRecord& r);

  // Algorithm 2 over elapsed_ms milliseconds at once: ages every record, drops those past the
  // allowed age; returns the ids dropped.
  std::vector<int> age(int elapsed_ms);

  // Removes an agent at once (e.g. it announced its landing); as an eviction.
  void drop(int id);
  // The record an agent was last evicted (or dropped) with, until a newer message brings it back;
  // null if none.
  const AgentRecord* evicted(int id) const;

  // This agent has landed: it no longer leads while an agent that flies is alive.
  void set_local_landed(bool landed) { local_landed_ = landed; }
  // The lowest id among the live agents that fly, this agent included; when every live agent has
  // landed, the lowest live id. Without landings this is the thesis's rule (lowest id alive).
  int leader() const;
  // Every live record has landed (true for an empty database).
  bool all_landed() const;
  const std::map<int, AgentRecord>& records() const { return records_; }
  // Ids of the agents heard directly (distance 1).
  std::vector<int> neighbours() const;
  // Bit i set for every live agent i (ids under 64), this agent included.
  uint64_t live_mask() const;

 private:
  int local_id_;
  std::function<int(int)> max_allowed_age_ms_;
  std::map<int, AgentRecord> records_;
  // each evicted agent's last record: only a newer sequence number brings it back
  std::map<int, AgentRecord> evicted_;
  bool local_landed_ = false;
};

}  // namespace uavsim::missions::coverage
