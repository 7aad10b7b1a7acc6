// The Agents Database (thesis 3.3): Algorithm 1 (merge) and Algorithm 2 (aging), the leader rule.
#include "agents_database.hpp"

#include <gtest/gtest.h>

#include <vector>

namespace uavsim::missions::coverage {
namespace {

// allowed age: 1000 ms + 500 ms per hop
AgentsDatabase make(int id) {
  return AgentsDatabase(id, [](int hops) { return 1000 + 500 * hops; });
}

AgentRecord rec(int id, uint16_t seq, double x, int hops = 0, int age = 0) {
  AgentRecord r;
  r.id = id;
  r.seq = seq;
  r.x_m = x;
  r.distance_hops = hops;
  r.age_ms = age;
  return r;
}

TEST(AgentsDatabase, MergesASendersCopyOneHopFarther) {
  AgentsDatabase adb = make(5);
  // agent 3 says: I am at x=3 (seq 10); I know 7 (1 hop, 100 ms old) and 5 (us: skipped)
  adb.on_message(rec(3, 10, 3.0), {rec(7, 4, 7.0, 1, 100), rec(5, 99, 5.0, 1, 0)});
  ASSERT_EQ(adb.records().size(), 2u);
  EXPECT_EQ(adb.records().at(3).distance_hops, 1);
  EXPECT_EQ(adb.records().at(3).age_ms, 0);
  EXPECT_EQ(adb.records().at(7).distance_hops, 2);
  EXPECT_EQ(adb.records().at(7).age_ms, 100);
  EXPECT_FALSE(adb.records().count(5));
}

TEST(AgentsDatabase, KeepsOnlyNewerSequenceNumbers) {
  AgentsDatabase adb = make(0);
  adb.merge(rec(2, 10, 1.0, 1));
  adb.merge(rec(2, 9, 2.0, 1));  // older: ignored
  EXPECT_EQ(adb.records().at(2).x_m, 1.0);
  adb.merge(rec(2, 11, 3.0, 3));  // newer, from farther away: taken
  EXPECT_EQ(adb.records().at(2).x_m, 3.0);
  EXPECT_EQ(adb.records().at(2).distance_hops, 3);
  // 16-bit wrap: 2 is newer than 65535
  adb.merge(rec(4, 65535, 0.0, 1));
  adb.merge(rec(4, 2, 4.0, 1));
  EXPECT_EQ(adb.records().at(4).x_m, 4.0);
  EXPECT_TRUE(seq_newer(2, 65535));
  EXPECT_FALSE(seq_newer(65535, 2));
  EXPECT_FALSE(seq_newer(7, 7));
}

TEST(AgentsDatabase, AgingEvictsByHopDistance) {
  AgentsDatabase adb = make(0);
  adb.merge(rec(1, 1, 0.0, 1, 0));             // allowed 1500 ms
  adb.merge(rec(2, 1, 0.0, 3, 500));           // allowed 2500 ms, already 500 old
  EXPECT_TRUE(adb.age(1500).empty());          // 1: 1500 <= 1500; 2: 2000
  EXPECT_EQ(adb.age(1), std::vector<int>{1});  // 1: 1501 > 1500
  EXPECT_TRUE(adb.age(499).empty());           // 2: 2500
  EXPECT_EQ(adb.age(1), std::vector<int>{2});
  EXPECT_TRUE(adb.records().empty());
}

TEST(AgentsDatabase, AStaleCopyCannotBringAnEvictedAgentBack) {
  AgentsDatabase adb = make(0);
  // a neighbour still carries 9 at 2 hops, 2400 ms old: 3 hops here, allowed 2500: taken
  adb.on_message(rec(1, 1, 0.0), {rec(9, 3, 0.0, 2, 2400)});
  EXPECT_TRUE(adb.records().count(9));
  adb.age(101);
  EXPECT_FALSE(adb.records().count(9));
  // the same stale copy again, now 2600 ms old: beyond the allowed age, not stored
  adb.on_message(rec(1, 2, 0.0), {rec(9, 3, 0.0, 2, 2600)});
  EXPECT_FALSE(adb.records().count(9));
}

// Agents 0, 1 and 2 hear each other; agent 9, which they knew, has gone silent (out of range, or
// dead). Each copy of 9's record that one of them takes back from another arrives a hop farther,
// and Algorithm 2 allows a farther record more age: as written (Algorithm 1 stores a record whose
// id is not in the ADB, whatever its sequence number), the three kept passing 9's last record
// around for ever, the hop count climbing by two a round trip. A recall's leader at the far end of
// the rectangle waited for the landed agents' answers without end (10 quads over 300 x 150 m, seed
// 3), and landed agents kept each other's radios on. An evicted agent comes back only with a newer
// message than the one it was evicted with.
TEST(AgentsDatabase, ASilentAgentsLastRecordDoesNotCirculateForEverAmongTheOthers) {
  std::vector<AgentsDatabase> adbs{make(0), make(1), make(2)};
  // 0 heard 9 directly, 1 through 0, 2 through 1: the farther copies may grow older
  for (int i = 0; i < 3; ++i) adbs[static_cast<size_t>(i)].merge(rec(9, 40, 0.0, i + 1, 0));
  std::vector<uint16_t> seq{0, 0, 0};
  double last_seen_s = 0.0;
  for (int tick = 1; tick <= 240; ++tick) {  // 30 s of 8 Hz broadcasts
    for (size_t i = 0; i < adbs.size(); ++i) {
      AgentRecord self = rec(static_cast<int>(i), ++seq[i], 0.0);
      std::vector<AgentRecord> copy;
      for (const auto& [id, r] : adbs[i].records()) copy.push_back(r);
      for (size_t j = 0; j < adbs.size(); ++j)
        if (j != i) adbs[j].on_message(self, copy);
    }
    for (AgentsDatabase& a : adbs) {
      a.age(125);
      if (a.records().count(9)) last_seen_s = tick * 0.125;
    }
  }
  // allowed 1500 ms at one hop, a little more through the others: gone within a few seconds
  EXPECT_LT(last_seen_s, 5.0);
  for (const AgentsDatabase& a : adbs) {
    EXPECT_FALSE(a.records().count(9));
    EXPECT_EQ(a.records().size(), 2u);  // the other two stay
  }
  // the record it was evicted with is kept (the leader reads where the agent was lost)
  ASSERT_NE(adbs[0].evicted(9), nullptr);
  EXPECT_EQ(adbs[0].evicted(9)->seq, 40);
  // 9 speaks again (a newer sequence number): back at once
  adbs[0].on_message(rec(9, 41, 0.0), {});
  EXPECT_TRUE(adbs[0].records().count(9));
  EXPECT_EQ(adbs[0].evicted(9), nullptr);
}

TEST(AgentsDatabase, LeaderIsTheLowestLiveIdAndIsReplacedWhenItAgesOut) {
  AgentsDatabase adb = make(4);
  EXPECT_EQ(adb.leader(), 4);  // alone
  adb.on_message(rec(6, 1, 0.0), {rec(2, 1, 0.0, 1, 0)});
  EXPECT_EQ(adb.leader(), 2);
  EXPECT_EQ(adb.live_mask(), (1u << 2) | (1u << 4) | (1u << 6));
  EXPECT_EQ(adb.neighbours(), std::vector<int>{6});
  // 2 falls silent, 6 keeps talking: after 2's allowed age (2 hops: 2000 ms) 4 leads
  for (int t = 0; t < 25; ++t) {
    adb.age(100);
    adb.on_message(rec(6, static_cast<uint16_t>(2 + t), 0.0), {});
  }
  EXPECT_EQ(adb.leader(), 4);
}

TEST(AgentsDatabase, LandedAgentsDoNotLeadWhileOneFlies) {
  AgentsDatabase adb = make(4);
  AgentRecord one = rec(1, 1, 0.0);
  one.landed = true;
  adb.on_message(one, {rec(6, 1, 0.0, 1, 0)});
  EXPECT_EQ(adb.leader(), 4);  // 1 has landed: the lowest id that flies
  EXPECT_FALSE(adb.all_landed());
  adb.set_local_landed(true);
  EXPECT_EQ(adb.leader(), 6);
  // every one landed: the thesis's rule again (the lowest live id)
  AgentRecord six = rec(6, 2, 0.0);
  six.landed = true;
  adb.on_message(six, {});
  EXPECT_TRUE(adb.all_landed());
  EXPECT_EQ(adb.leader(), 1);
  EXPECT_EQ(adb.live_mask(), (1u << 1) | (1u << 4) | (1u << 6));  // landed agents still answer
}

}  // namespace
}  // namespace uavsim::missions::coverage
