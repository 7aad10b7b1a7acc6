#include "sim/events.hpp"

#include <gtest/gtest.h>

namespace uavsim::server::sim {
namespace {

// fills the log with n events, alternating armed/disarmed, one per 0.1 s
void record(EventLog& log, size_t n) {
  for (size_t k = 0; k < n; ++k) {
    log.add(0.1 * static_cast<double>(k), k % 2 == 0 ? EventType::kArmed : EventType::kDisarmed, 0,
            "");
  }
}

TEST(EventLog, HoldsTheLatestEventsWhileSeqNumbersAndCountsGoOn) {
  constexpr size_t kOver = 100;
  EventLog log;
  record(log, EventLog::kCapacity + kOver);
  // the first kOver events were dropped: the log holds seq kOver .. kCapacity + kOver - 1
  ASSERT_EQ(log.recent().size(), EventLog::kCapacity);
  EXPECT_EQ(log.first_seq(), kOver);
  EXPECT_EQ(log.next_seq(), EventLog::kCapacity + kOver);
  EXPECT_EQ(log.recent().front().seq, kOver);
  EXPECT_EQ(log.recent().back().seq, EventLog::kCapacity + kOver - 1);
  // counts are of everything recorded, dropped events included: half armed, half disarmed
  EXPECT_EQ(log.count(EventType::kArmed), (EventLog::kCapacity + kOver) / 2);
  EXPECT_EQ(log.count(EventType::kDisarmed), (EventLog::kCapacity + kOver) / 2);
  EXPECT_EQ(log.count(EventType::kCrash), 0u);
}

TEST(EventLog, SinceADroppedSeqStartsAtTheOldestHeld) {
  constexpr size_t kOver = 10;
  EventLog log;
  record(log, EventLog::kCapacity + kOver);
  const std::vector<Event> from0 = log.since(0);
  ASSERT_EQ(from0.size(), EventLog::kCapacity);
  EXPECT_EQ(from0.front().seq, kOver);
  const std::vector<Event> tail = log.since(EventLog::kCapacity + kOver - 3);
  ASSERT_EQ(tail.size(), 3u);
  EXPECT_EQ(tail.front().seq, EventLog::kCapacity + kOver - 3);
  EXPECT_TRUE(log.since(log.next_seq()).empty());
}

TEST(EventLog, ClearStartsTheSeqNumbersAndCountsAgain) {
  EventLog log;
  record(log, EventLog::kCapacity + 1);
  log.clear();
  EXPECT_TRUE(log.recent().empty());
  EXPECT_EQ(log.first_seq(), 0u);
  EXPECT_EQ(log.next_seq(), 0u);
  EXPECT_EQ(log.count(EventType::kArmed), 0u);
  EXPECT_EQ(log.add(1.0, EventType::kCrash, 2, "hit").seq, 0u);
}

}  // namespace
}  // namespace uavsim::server::sim
