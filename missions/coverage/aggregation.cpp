#include "aggregation.hpp"

namespace uavsim::missions::coverage {

namespace {
uint64_t bit(int id) { return id >= 0 && id < 64 ? uint64_t{1} << id : 0; }
}  // namespace

AggregationNode::AggregationNode(int local_id, int stripes) : local_id_(local_id), apd_(stripes) {}

void AggregationNode::start(uint16_t query_id, const AreaParts& own) {
  active_ = true;
  origin_ = local_id_;
  query_id_ = query_id;
  version_ = 0;
  responded_ = bit(local_id_);
  merged_from_ = 0;
  apd_ = own;
  heard_.clear();
  changed();
}

void AggregationNode::changed() {
  ++version_;
  dirty_ = true;
}

bool AggregationNode::on_message(const AggregateMessage& m, int leader_id, const AreaParts& own) {
  // only the current leader's queries count
  if (m.origin != leader_id || m.sender == local_id_) return false;
  if (m.apd.stripe_count() != apd_.stripe_count()) return false;
  const bool same_query = active_ && origin_ == m.origin && query_id_ == m.query_id;
  // a query of this origin no newer than ours (a late retransmission, or one we left) is ignored
  if (!same_query && origin_ == m.origin && !seq_newer_query(m.query_id)) return false;
  bool joined = false;
  if (!same_query) {
    // join: our own APD is the first part of our answer
    active_ = true;
    origin_ = m.origin;
    query_id_ = m.query_id;
    version_ = 0;
    responded_ = bit(local_id_);
    merged_from_ = 0;
    apd_ = own;
    heard_.clear();
    joined = true;
  }
  heard_[m.sender] = {m.responded, (m.acked & bit(local_id_)) != 0};
  // merge: the union of the areas and of the responded sets (Algorithm 4)
  const uint64_t before_responded = responded_;
  bool area_grew = false;
  apd_.merge(m.apd, &area_grew);
  const bool grew = area_grew || (responded_ | m.responded) != before_responded;
  responded_ |= m.responded;
  merged_from_ |= bit(m.sender);
  if (grew || joined) changed();
  return grew || joined;
}

bool AggregationNode::seq_newer_query(uint16_t candidate) const {
  const uint16_t d = static_cast<uint16_t>(candidate - query_id_);
  return d != 0 && d < 0x8000;
}

void AggregationNode::refresh_own(const AreaParts& own) {
  if (!active_) return;
  bool grew = false;
  apd_.merge(own, &grew);
  if (grew) changed();
}

bool AggregationNode::acknowledged_by(int neighbour) const {
  const auto it = heard_.find(neighbour);
  if (it == heard_.end()) return false;
  // it merged our message, and has everything we have responded
  return it->second.acked_us && (it->second.responded & responded_) == responded_;
}

std::optional<AggregateMessage> AggregationNode::poll(double now_s,
                                                      const std::vector<int>& neighbours,
                                                      double retransmit_s) {
  AggregateMessage m;
  if (!poll(now_s, neighbours, retransmit_s, &m)) return std::nullopt;
  return m;
}

bool AggregationNode::poll(double now_s, const std::vector<int>& neighbours, double retransmit_s,
                           AggregateMessage* out) {
  if (!active_) return false;
  bool due = dirty_;
  if (!due && now_s - last_sent_s_ >= retransmit_s) {
    for (int n : neighbours) {
      if (!acknowledged_by(n)) {
        due = true;
        break;
      }
    }
  }
  if (!due) return false;
  dirty_ = false;
  last_sent_s_ = now_s;
  ++sent_;
  out->sender = local_id_;
  out->origin = origin_;
  out->query_id = query_id_;
  out->version = version_;
  out->responded = responded_;
  out->acked = merged_from_;
  out->apd = apd_;
  return true;
}

}  // namespace uavsim::missions::coverage
