// The aggregation query of thesis 3.4: partial aggregation along a chain, the acknowledgement list
// that ends retransmissions, and messages of other origins ignored.
#include "aggregation.hpp"

#include <gtest/gtest.h>

#include <map>

namespace uavsim::missions::coverage {
namespace {

constexpr int kStripes = 4;

AreaParts apd_with(int stripe, Interval iv) {
  AreaParts a(kStripes);
  a.add(stripe, iv);
  return a;
}

// A chain 0 - 1 - 2 - 3 (each hears only its neighbours, fig. 3.8's kind of graph), perfect links:
// polls every 0.1 s, delivers what was sent to the neighbours.
struct Chain {
  std::vector<AreaParts> own;
  std::vector<AggregationNode> nodes;
  explicit Chain(int n) {
    for (int i = 0; i < n; ++i) {
      own.push_back(apd_with(i % kStripes, {10.0 * i, 10.0 * i + 10.0}));
      nodes.emplace_back(i, kStripes);
    }
  }
  std::vector<int> neighbours(int i) const {
    std::vector<int> v;
    if (i > 0) v.push_back(i - 1);
    if (i + 1 < static_cast<int>(nodes.size())) v.push_back(i + 1);
    return v;
  }
  // one round; returns how many messages were sent
  int round(double now, int leader) {
    std::vector<std::pair<int, AggregateMessage>> sent;
    for (size_t i = 0; i < nodes.size(); ++i) {
      if (auto m = nodes[i].poll(now, neighbours(static_cast<int>(i)), 0.5))
        sent.emplace_back(static_cast<int>(i), *m);
    }
    for (const auto& [from, m] : sent) {
      for (int to : neighbours(from))
        nodes[static_cast<size_t>(to)].on_message(m, leader, own[static_cast<size_t>(to)]);
    }
    return static_cast<int>(sent.size());
  }
};

TEST(Aggregation, ChainQueryCompletesWithTheUnionAndRetransmissionsStop) {
  Chain chain(4);
  chain.nodes[0].start(1, chain.own[0]);
  const uint64_t live = 0b1111;
  int rounds = 0, total = 0;
  while (!chain.nodes[0].complete(live) && rounds < 100) total += chain.round(0.1 * rounds++, 0);
  ASSERT_TRUE(chain.nodes[0].complete(live));
  // the leader's message needs 3 hops out, the answer 3 hops back
  EXPECT_LE(rounds, 8);
  AreaParts expected(kStripes);
  for (const auto& o : chain.own) expected.merge(o);
  EXPECT_EQ(chain.nodes[0].result(), expected);
  // once everyone has everything and every neighbour acknowledged, nobody sends any more
  int quiet_after = -1;
  for (int r = 0; r < 60; ++r) {
    if (chain.round(10.0 + 0.1 * r, 0) == 0 && quiet_after < 0) quiet_after = r;
  }
  ASSERT_GE(quiet_after, 0);
  EXPECT_EQ(chain.round(20.0, 0), 0);
  EXPECT_EQ(chain.round(30.0, 0), 0);
  EXPECT_LT(total, 40);
}

TEST(Aggregation, MessagesOfAnotherOriginAreIgnored) {
  AggregationNode n(2, kStripes);
  AggregateMessage m;
  m.sender = 1;
  m.origin = 1;
  m.query_id = 1;
  m.responded = 0b10;
  m.apd = apd_with(0, {0, 5});
  EXPECT_FALSE(n.on_message(m, /*leader_id=*/0, AreaParts(kStripes)));
  EXPECT_FALSE(n.active());
  EXPECT_TRUE(n.on_message(m, /*leader_id=*/1, apd_with(1, {0, 5})));
  EXPECT_TRUE(n.active());
  EXPECT_EQ(n.responded(), 0b110u);
  EXPECT_TRUE(n.result().stripe_covers(0, {0, 5}));
  EXPECT_TRUE(n.result().stripe_covers(1, {0, 5}));
  // an older query of the same origin is a late retransmission: ignored
  m.query_id = 0;
  EXPECT_FALSE(n.on_message(m, 1, AreaParts(kStripes)));
  EXPECT_EQ(n.query_id(), 1);
  // a newer one starts afresh from the own APD (a failed agent's data does not survive)
  m.query_id = 2;
  m.responded = 0b10;
  m.apd = AreaParts(kStripes);
  EXPECT_TRUE(n.on_message(m, 1, apd_with(3, {1, 2})));
  EXPECT_FALSE(n.result().stripe_covers(0, {0, 5}));
  EXPECT_TRUE(n.result().stripe_covers(3, {1, 2}));
}

TEST(Aggregation, RetransmitsUntilAcknowledged) {
  AggregationNode leader(0, kStripes);
  leader.start(7, apd_with(0, {0, 1}));
  EXPECT_TRUE(leader.poll(0.0, {1}, 0.5));   // new: at once
  EXPECT_FALSE(leader.poll(0.2, {1}, 0.5));  // within the period
  EXPECT_TRUE(leader.poll(0.5, {1}, 0.5));   // retransmission
  // agent 1 answers: it merged ours (acked bit 0) and has responded {0, 1}
  AggregateMessage reply;
  reply.sender = 1;
  reply.origin = 0;
  reply.query_id = 7;
  reply.responded = 0b11;
  reply.acked = 0b01;
  reply.apd = apd_with(1, {0, 1});
  leader.on_message(reply, 0, apd_with(0, {0, 1}));
  EXPECT_TRUE(leader.complete(0b11));
  EXPECT_TRUE(leader.poll(0.6, {1}, 0.5));  // our content changed: sent once more
  // 1 now hears {0,1} from us, and its ack of our new message arrives
  reply.acked = 0b01;
  leader.on_message(reply, 0, apd_with(0, {0, 1}));
  EXPECT_FALSE(leader.poll(5.0, {1}, 0.5));  // acknowledged: quiet
}

// poll() into a message the caller keeps: the same message as the one poll() returns, whatever
// the kept one held before (a larger map, another query).
TEST(Aggregation, PollIntoAKeptMessageGivesTheSameMessage) {
  AggregationNode a(2, kStripes), b(2, kStripes);
  AreaParts own(kStripes);
  own.add(1, {0, 5});
  a.start(3, own);
  b.start(3, own);
  AggregateMessage kept;
  kept.apd = AreaParts(kStripes);
  for (int s = 0; s < kStripes; ++s) kept.apd.add(s, {10.0 * s, 10.0 * s + 3.0});
  kept.responded = 0xFF;
  const auto m = a.poll(0.0, {1}, 0.5);
  ASSERT_TRUE(m);
  ASSERT_TRUE(b.poll(0.0, {1}, 0.5, &kept));
  EXPECT_EQ(kept.apd, m->apd);
  EXPECT_EQ(kept.sender, m->sender);
  EXPECT_EQ(kept.origin, m->origin);
  EXPECT_EQ(kept.query_id, m->query_id);
  EXPECT_EQ(kept.version, m->version);
  EXPECT_EQ(kept.responded, m->responded);
  EXPECT_EQ(kept.acked, m->acked);
  // nothing due: the kept message stays as it was
  const AggregateMessage before = kept;
  EXPECT_FALSE(b.poll(0.1, {1}, 0.5, &kept));
  EXPECT_EQ(kept.apd, before.apd);
  EXPECT_EQ(kept.version, before.version);
}

}  // namespace
}  // namespace uavsim::missions::coverage
