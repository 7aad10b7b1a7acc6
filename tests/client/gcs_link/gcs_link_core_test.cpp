#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <map>
#include <random>
#include <set>
#include <vector>

#include "uavsim/client/gcs_link.hpp"

namespace uavsim::client {
namespace {

constexpr int64_t kStep_us = 1000;      // the test drives both ends every 1 ms
constexpr int64_t kPeriod_us = 100000;  // 10 Hz, the default
constexpr uint16_t kQueued = 0x0001;
constexpr uint16_t kLatest = 0x8001;

// One direction of a seeded lossy channel: each packet is dropped with probability loss, or
// delivered after a uniform delay in [min, max], unless the channel is in an outage.
class Channel {
 public:
  Channel(uint64_t seed, double loss, int64_t min_delay_us, int64_t max_delay_us)
      : rng_(seed), loss_(loss), min_us_(min_delay_us), max_us_(max_delay_us) {}
  void set_outage(bool down) { down_ = down; }
  void send(std::vector<uint8_t> packet, int64_t now_us) {
    ++sent_;
    const double u = std::uniform_real_distribution<double>(0.0, 1.0)(rng_);
    if (down_ || u < loss_) return;
    const int64_t delay = std::uniform_int_distribution<int64_t>(min_us_, max_us_)(rng_);
    flight_.emplace(now_us + delay, std::move(packet));
  }
  // Packets due by now_us, handed to the receiver with their arrival time.
  void deliver(GcsLinkCore& to, int64_t now_us) {
    while (!flight_.empty() && flight_.begin()->first <= now_us) {
      const auto& [t, p] = *flight_.begin();
      EXPECT_EQ(to.on_packet(p.data(), p.size(), t), GcsLinkStatus::kOk);
      flight_.erase(flight_.begin());
    }
  }
  uint64_t sent() const { return sent_; }

 private:
  std::mt19937_64 rng_;
  double loss_;
  int64_t min_us_, max_us_;
  bool down_ = false;
  std::multimap<int64_t, std::vector<uint8_t>> flight_;
  uint64_t sent_ = 0;
};

// A UAV (id 3) and the GCS; the GCS's clock reads uav_clock - offset_us.
struct Link {
  GcsLinkCore uav{GcsLinkConfig{3}};
  GcsLinkCore gcs{GcsLinkConfig{kGcsId}};
  Channel up, down;
  int64_t offset_us;
  int64_t now_us = 0;  // UAV clock
  std::vector<GcsMessage> at_gcs, at_uav;

  Link(double loss, int64_t min_delay_us, int64_t max_delay_us, int64_t offset)
      : up(1, loss, min_delay_us, max_delay_us),
        down(2, loss, min_delay_us, max_delay_us),
        offset_us(offset) {}

  void step() {
    now_us += kStep_us;
    up.deliver(gcs, now_us - offset_us);
    down.deliver(uav, now_us);
    if (auto p = uav.poll(now_us)) up.send(std::move(*p), now_us - offset_us);
    if (auto p = gcs.poll(now_us - offset_us)) down.send(std::move(*p), now_us);
    for (GcsMessage& m : gcs.take_received()) at_gcs.push_back(std::move(m));
    for (GcsMessage& m : uav.take_received()) at_uav.push_back(std::move(m));
  }
  void run_for(double seconds) {
    for (int64_t k = 0; k < static_cast<int64_t>(seconds * 1e6) / kStep_us; ++k) step();
  }
};

std::vector<uint8_t> counter(uint32_t n) {
  return {uint8_t(n >> 24), uint8_t(n >> 16), uint8_t(n >> 8), uint8_t(n)};
}
uint32_t counter_of(const std::vector<uint8_t>& b) {
  return (uint32_t{b[0]} << 24) | (uint32_t{b[1]} << 16) | (uint32_t{b[2]} << 8) | b[3];
}

TEST(GcsLinkCore, UnderThirtyPercentLossEveryQueuedMessageArrivesOnce) {
  Link link(0.3, 5000, 80000, 0);
  constexpr uint32_t kUp = 300, kDown = 100;
  uint32_t up = 0, down = 0, latest = 0;
  // 20 s of traffic: queued messages both ways, a latest-only position every 10 ms
  for (int k = 0; k < 20000; ++k) {
    if (k % 50 == 0 && up < kUp)
      ASSERT_EQ(link.uav.publish(kQueued, counter(up++)), GcsLinkStatus::kOk);
    if (k % 200 == 0 && down < kDown)
      ASSERT_EQ(link.gcs.publish(kQueued, counter(down++)), GcsLinkStatus::kOk);
    if (k % 10 == 0) ASSERT_EQ(link.uav.publish(kLatest, counter(latest++)), GcsLinkStatus::kOk);
    ASSERT_LE(link.uav.pending(kLatest), 1u);  // never more than the latest one kept
    link.step();
  }
  link.run_for(10.0);  // quiet: retransmissions catch up

  std::set<uint32_t> got_up;
  std::vector<uint32_t> got_latest;
  for (const GcsMessage& m : link.at_gcs) {
    EXPECT_EQ(m.from, 3);
    if (m.topic == kQueued) {
      EXPECT_TRUE(got_up.insert(counter_of(m.payload)).second) << "delivered twice";
    } else {
      got_latest.push_back(counter_of(m.payload));
    }
  }
  EXPECT_EQ(got_up.size(), kUp);
  EXPECT_EQ(*got_up.rbegin(), kUp - 1);
  std::set<uint32_t> got_down;
  for (const GcsMessage& m : link.at_uav) got_down.insert(counter_of(m.payload));
  EXPECT_EQ(got_down.size(), kDown);
  // latest only: the last position arrives, most never do (10 per period, one packet per period)
  ASSERT_FALSE(got_latest.empty());
  EXPECT_EQ(got_latest.back(), latest - 1);
  EXPECT_LT(got_latest.size(), latest / 5);
  EXPECT_GT(link.uav.stats().messages_superseded, latest / 2);
  EXPECT_GT(link.uav.stats().retransmissions, 0u);
  EXPECT_EQ(link.uav.pending(), 0u);
  EXPECT_EQ(link.gcs.pending(), 0u);
}

TEST(GcsLinkCore, OnlyTheLatestMessageOfALatestOnlyTopicIsSent) {
  Link link(0.0, 1000, 1000, 0);
  link.step();  // the first packet goes out at once; the next period is 100 ms later
  for (uint32_t k = 0; k < 10; ++k)
    ASSERT_EQ(link.uav.publish(kLatest, counter(k)), GcsLinkStatus::kOk);
  ASSERT_EQ(link.uav.publish(kQueued, counter(42)), GcsLinkStatus::kOk);
  ASSERT_EQ(link.uav.publish(kQueued, counter(43)), GcsLinkStatus::kOk);
  link.run_for(0.5);
  std::vector<std::pair<uint16_t, uint32_t>> got;
  for (const GcsMessage& m : link.at_gcs) got.emplace_back(m.topic, counter_of(m.payload));
  EXPECT_EQ(got, (std::vector<std::pair<uint16_t, uint32_t>>{
                     {kLatest, 9}, {kQueued, 42}, {kQueued, 43}}));
  EXPECT_EQ(link.uav.stats().messages_superseded, 9u);
}

TEST(GcsLinkCore, AnOutageFollowedByRecoveryLosesNothingQueued) {
  Link link(0.0, 20000, 20000, 0);
  link.run_for(1.0);
  link.up.set_outage(true);
  link.down.set_outage(true);
  // 30 s without a link: 600 queued messages (more than fit in one packet) and positions pile up
  uint32_t latest = 0;
  for (int k = 0; k < 30000; ++k) {
    if (k % 50 == 0) ASSERT_EQ(link.uav.publish(kQueued, counter(k / 50)), GcsLinkStatus::kOk);
    if (k % 10 == 0) link.uav.publish(kLatest, counter(latest++));
    link.step();
  }
  EXPECT_TRUE(link.at_gcs.empty());
  EXPECT_EQ(link.uav.pending(), 601u);  // 600 queued + the latest position
  link.up.set_outage(false);
  link.down.set_outage(false);
  link.run_for(10.0);
  std::vector<uint32_t> queued, positions;
  for (const GcsMessage& m : link.at_gcs)
    (m.topic == kQueued ? queued : positions).push_back(counter_of(m.payload));
  ASSERT_EQ(queued.size(), 600u);
  for (uint32_t k = 0; k < 600; ++k) EXPECT_EQ(queued[k], k);  // in order: oldest first, one delay
  EXPECT_EQ(positions, std::vector<uint32_t>{latest - 1});
  EXPECT_EQ(link.uav.pending(), 0u);
  // rate limited: 600 messages of 12 bytes in 1400-byte packets need several periods
  EXPECT_GT(link.uav.stats().packets_sent, 0u);
}

TEST(GcsLinkCore, ClockOffsetConvergesWithinOnePeriod) {
  // the GCS clock is 1234.5678 s behind the UAV's; delays 5..300 ms, 30% loss
  constexpr int64_t kOffset_us = 1234567800;
  Link link(0.3, 5000, 300000, kOffset_us);
  EXPECT_FALSE(link.uav.clock_offset_us());
  link.run_for(0.5);
  ASSERT_TRUE(link.uav.clock_offset_us());
  link.run_for(20.0);
  const int64_t error_us = *link.uav.clock_offset_us() - kOffset_us;
  // Algorithm 6 over-estimates by the shortest delay seen: never below the truth, within a period
  EXPECT_GE(error_us, 5000);
  EXPECT_LE(error_us, kPeriod_us);
  // conversions use the estimate: local -> GCS -> local is the identity
  EXPECT_EQ(*link.uav.to_gcs_time_us(5000000), 5000000 - *link.uav.clock_offset_us());
  EXPECT_EQ(*link.uav.to_local_time_us(*link.uav.to_gcs_time_us(5000000)), 5000000);
  EXPECT_FALSE(link.gcs.clock_offset_us());  // the GCS is the reference
}

TEST(GcsLinkCore, OnePacketPerPeriod) {
  GcsLinkCore core(GcsLinkConfig{1});
  int packets = 0;
  for (int64_t t = 0; t < 1000000; t += kStep_us) packets += core.poll(t) ? 1 : 0;
  EXPECT_EQ(packets, 10);  // t = 0, 0.1, ..., 0.9 s
}

TEST(GcsLinkCore, PacketsStayWithinTheirSizeLimit) {
  GcsLinkConfig c{1};
  c.max_packet_bytes = 300;
  GcsLinkCore core(c);
  for (int k = 0; k < 100; ++k)
    ASSERT_EQ(core.publish(kQueued, std::vector<uint8_t>(50, 1)), GcsLinkStatus::kOk);
  const auto p = core.poll(0);
  ASSERT_TRUE(p);
  EXPECT_LE(p->size(), 300u);
  // header 20 + 4 * (8 + 50) = 252: four messages fit
  EXPECT_EQ(p->size(), 252u);
  EXPECT_EQ(core.publish(kQueued, std::vector<uint8_t>(400, 1)), GcsLinkStatus::kPayloadTooLarge);
}

TEST(GcsLinkCore, AFullQueueRefusesMessages) {
  GcsLinkConfig c{1};
  c.max_queued_messages = 3;
  GcsLinkCore core(c);
  for (int k = 0; k < 3; ++k) ASSERT_EQ(core.publish(kQueued, {1}), GcsLinkStatus::kOk);
  EXPECT_EQ(core.publish(kQueued, {1}), GcsLinkStatus::kQueueFull);
}

TEST(GcsLinkCore, MalformedPacketsAreCountedAndChangeNothing) {
  GcsLinkCore sender(GcsLinkConfig{kGcsId});
  ASSERT_EQ(sender.publish(kQueued, {1, 2, 3}), GcsLinkStatus::kOk);
  const std::vector<uint8_t> good = *sender.poll(5);
  GcsLinkCore core(GcsLinkConfig{1});
  const std::vector<std::vector<uint8_t>> bad = {
      {},
      {'U', 'G'},
      std::vector<uint8_t>(good.begin(), good.end() - 1),  // truncated payload
      [&] {
        auto b = good;
        b[0] = 'X';
        return b;
      }(),  // magic
      [&] {
        auto b = good;
        b[2] = 9;
        return b;
      }(),  // version
      [&] {
        auto b = good;
        b[19] = 7;
        return b;
      }(),  // more messages than the packet holds
      [&] {
        auto b = good;
        b.push_back(0);
        return b;
      }(),  // trailing bytes
  };
  for (const auto& b : bad)
    EXPECT_EQ(core.on_packet(b.data(), b.size(), 100), GcsLinkStatus::kMalformed);
  EXPECT_EQ(core.stats().packets_malformed, bad.size());
  EXPECT_TRUE(core.take_received().empty());
  EXPECT_FALSE(core.clock_offset_us());
  EXPECT_EQ(core.on_packet(good.data(), good.size(), 100), GcsLinkStatus::kOk);
  EXPECT_EQ(core.take_received().size(), 1u);
  EXPECT_EQ(*core.clock_offset_us(), 95);
}

TEST(GcsLinkCore, ARetransmittedMessageIsDeliveredOnce) {
  GcsLinkCore a(GcsLinkConfig{1}), b(GcsLinkConfig{kGcsId});
  ASSERT_EQ(a.publish(kQueued, {9}), GcsLinkStatus::kOk);
  const auto first = *a.poll(0);
  const auto again = *a.poll(kPeriod_us);  // not acknowledged yet: sent again
  EXPECT_EQ(b.on_packet(first.data(), first.size(), 0), GcsLinkStatus::kOk);
  EXPECT_EQ(b.on_packet(again.data(), again.size(), 0), GcsLinkStatus::kOk);
  EXPECT_EQ(b.take_received().size(), 1u);
  EXPECT_EQ(b.stats().duplicates, 1u);
  EXPECT_EQ(a.stats().retransmissions, 1u);
  const auto ack = *b.poll(0);
  EXPECT_EQ(a.on_packet(ack.data(), ack.size(), 0), GcsLinkStatus::kOk);
  EXPECT_EQ(a.pending(), 0u);
}

}  // namespace
}  // namespace uavsim::client
