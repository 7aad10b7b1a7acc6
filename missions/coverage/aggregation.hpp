// The leader's distributed aggregation query (the thesis the project descends from, section 3.4):
// the leader starts a query with its own APD; every agent that hears a message of the current
// leader's query merges it with its own APD and what it had gathered, and broadcasts the result; a
// message naming every live agent as responded eventually reaches the leader, whose APD field is
// then the flock's coverage map. Messages of another origin (not our leader) are ignored. Every
// agent re-broadcasts its latest message at a fixed rate until all its direct neighbours have
// acknowledged it: each message lists the agents whose messages its sender has merged (acked); a
// neighbour whose message lists us and has responded at least everything we have needs nothing more
// from us. Pure.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <vector>

#include "area_parts.hpp"

namespace uavsim::missions::coverage {

struct AggregateMessage {
  int sender = 0;
  int origin = 0;          // the leader that started the query
  uint16_t query_id = 0;   // the origin's query counter
  uint16_t version = 0;    // the sender's message counter within the query
  uint64_t responded = 0;  // bit i: agent i's APD is included
  uint64_t acked = 0;      // bit i: the sender has merged agent i's latest message
  AreaParts apd = AreaParts(0);
};

class AggregationNode {
 public:
  AggregationNode(int local_id, int stripes);

  // Leader: starts query `query_id` with the own APD (a new, higher id than any before).
  void start(uint16_t query_id, const AreaParts& own);
  // A complete message heard on the radio; leader_id is who this agent currently follows. Returns
  // true when it joined or changed this agent's part in a query.
  bool on_message(const AggregateMessage& m, int leader_id, const AreaParts& own);
  // Keeps the own APD in the partial result (pictures taken while a query runs).
  void refresh_own(const AreaParts& own);

  // The message to broadcast now, if any: at once after a change, then every retransmit_s until
  // every id in `neighbours` has acknowledged it.
  std::optional<AggregateMessage> poll(double now_s, const std::vector<int>& neighbours,
                                       double retransmit_s);
  // The same, written into *out (false: nothing to send, *out untouched): a caller that keeps
  // *out between polls reuses its memory (the map is copied into the lists already there).
  bool poll(double now_s, const std::vector<int>& neighbours, double retransmit_s,
            AggregateMessage* out);

  bool active() const { return active_; }
  int origin() const { return origin_; }
  uint16_t query_id() const { return query_id_; }
  uint64_t responded() const { return responded_; }
  const AreaParts& result() const { return apd_; }
  // Leader: every agent of live_mask has responded.
  bool complete(uint64_t live_mask) const {
    return active_ && (responded_ & live_mask) == live_mask;
  }
  // Ends this agent's part (stops retransmitting).
  void stop() { active_ = false; }
  // Number of messages poll() returned (the query's radio cost).
  int sent() const { return sent_; }

 private:
  bool acknowledged_by(int neighbour) const;
  bool seq_newer_query(uint16_t candidate) const;
  void changed();

  int local_id_;
  bool active_ = false;
  int origin_ = -1;
  uint16_t query_id_ = 0;
  uint16_t version_ = 0;
  uint64_t responded_ = 0;
  uint64_t merged_from_ = 0;  // the acked list: senders whose latest message is merged
  AreaParts apd_;
  bool dirty_ = false;
  double last_sent_s_ = -1e9;
  int sent_ = 0;
  // per neighbour: its latest message's responded set and whether it listed us as acked
  struct Heard {
    uint64_t responded = 0;
    bool acked_us = false;
  };
  std::map<int, Heard> heard_;
};

}  // namespace uavsim::missions::coverage
