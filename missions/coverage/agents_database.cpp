#include "agents_database.hpp"

#include <utility>

namespace uavsim::missions::coverage {

bool seq_newer(uint16_t a, uint16_t b) {
  // a is newer when it is ahead of b by less than half the sequence space
  const uint16_t d = static_cast<uint16_t>(a - b);
  return d != 0 && d < 0x8000;
}

AgentsDatabase::AgentsDatabase(int local_id, std::function<int(int)> max_allowed_age_ms)
    : local_id_(local_id), max_allowed_age_ms_(std::move(max_allowed_age_ms)) {}

void AgentsDatabase::on_message(const AgentRecord& sender,
                                const std::vector<AgentRecord>& sender_adb) {
  if (sender.id == local_id_) return;
  for (AgentRecord r : sender_adb) {
    if (r.id == local_id_ || r.id == sender.id) continue;
    r.distance_hops += 1;
    merge(r);
  }
  AgentRecord s = sender;
  s.distance_hops = 1;
  s.age_ms = 0;
  merge(s);
}

void AgentsDatabase::merge(const AgentRecord& r) {
  if (r.id == local_id_ || r.age_ms > max_allowed_age_ms_(r.distance_hops)) return;
  if (auto gone = evicted_.find(r.id); gone != evicted_.end()) {
    if (!seq_newer(r.seq, gone->second.seq)) return;  // a copy of what was evicted: not back
    evicted_.erase(gone);
  }
  auto it = records_.find(r.id);
  if (it == records_.end() || seq_newer(r.seq, it->second.seq)) records_[r.id] = r;
}

void AgentsDatabase::drop(int id) {
  if (auto it = records_.find(id); it != records_.end()) {
    evicted_[id] = it->second;
    records_.erase(it);
  }
}

const AgentRecord* AgentsDatabase::evicted(int id) const {
  const auto it = evicted_.find(id);
  return it == evicted_.end() ? nullptr : &it->second;
}

std::vector<int> AgentsDatabase::age(int elapsed_ms) {
  std::vector<int> dropped;
  for (auto it = records_.begin(); it != records_.end();) {
    const int new_age = it->second.age_ms + elapsed_ms;
    if (new_age <= max_allowed_age_ms_(it->second.distance_hops)) {
      it->second.age_ms = new_age;
      ++it;
    } else {
      dropped.push_back(it->first);
      evicted_[it->first] = it->second;
      it = records_.erase(it);
    }
  }
  return dropped;
}

int AgentsDatabase::leader() const {
  // records_ is ordered by id: the first one that flies is the lowest other id that flies
  int lowest_flying = local_landed_ ? -1 : local_id_;
  for (const auto& [id, r] : records_) {
    if (r.landed) continue;
    if (lowest_flying < 0 || id < lowest_flying) lowest_flying = id;
    break;
  }
  if (lowest_flying >= 0) return lowest_flying;
  if (records_.empty() || records_.begin()->first > local_id_) return local_id_;
  return records_.begin()->first;
}

bool AgentsDatabase::all_landed() const {
  for (const auto& [id, r] : records_)
    if (!r.landed) return false;
  return true;
}

std::vector<int> AgentsDatabase::neighbours() const {
  std::vector<int> ids;
  for (const auto& [id, r] : records_)
    if (r.distance_hops == 1) ids.push_back(id);
  return ids;
}

uint64_t AgentsDatabase::live_mask() const {
  uint64_t mask = 0;
  if (local_id_ >= 0 && local_id_ < 64) mask |= uint64_t{1} << local_id_;
  for (const auto& [id, r] : records_)
    if (id >= 0 && id < 64) mask |= uint64_t{1} << id;
  return mask;
}

}  // namespace uavsim::missions::coverage
