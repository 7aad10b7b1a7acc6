// The flock's radio frames: beacons and fragmented aggregation messages within 127 bytes.
#include "radio_messages.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace uavsim::missions::coverage {
namespace {

TEST(RadioMessages, BeaconRoundTripsWithinAFrame) {
  const RadioFrameOrigin o{100.0, -50.0};
  Beacon b;
  b.self = {3, 65000, 123.45, -40.0, -1.5, 4.9, -0.3, 0, 0};
  b.going_home = true;
  for (int i = 0; i < 9; ++i) b.records.push_back({10 + i, 7, 200.0 + i, 0.0, 3.1, 0, 0, 2, 1500});
  const Frame f = encode_beacon(b, o);
  EXPECT_EQ(f.size(), 14u + 14u * kRecordsPerBeacon);  // 126: at most 8 records
  EXPECT_LE(f.size(), kMaxFrameBytes);
  const auto d = decode_beacon(f, o);
  ASSERT_TRUE(d);
  EXPECT_EQ(d->self.id, 3);
  EXPECT_EQ(d->self.seq, 65000);
  EXPECT_NEAR(d->self.x_m, 123.5, 0.051);  // 0.1 m steps
  EXPECT_NEAR(d->self.y_m, -40.0, 0.051);
  EXPECT_NEAR(d->self.heading_rad, -1.5, 1e-4);
  EXPECT_NEAR(d->self.vx_m_s, 4.9, 1e-9);
  EXPECT_NEAR(d->self.vy_m_s, -0.3, 1e-9);
  EXPECT_TRUE(d->going_home);
  ASSERT_EQ(d->records.size(), 8u);
  EXPECT_EQ(d->records[6].id, 16);
  EXPECT_EQ(d->records[6].distance_hops, 2);
  EXPECT_EQ(d->records[6].age_ms, 1500);
  EXPECT_NEAR(d->records[6].heading_rad, 3.1, 1e-4);
}

TEST(RadioMessages, BeaconCarriesLandedFlagsAndTheSurveyRound) {
  const RadioFrameOrigin o{0.0, 0.0};
  Beacon b;
  b.self = {5, 9, 1.0, 2.0, 0.0, 0, 0, 0, 0, true};
  b.round = 6;
  AgentRecord far{7, 3, 0.0, 0.0, 0.0, 0, 0, 127, 200, true};
  AgentRecord flying{8, 4, 0.0, 0.0, 0.0, 0, 0, 3, 100, false};
  b.records = {far, flying};
  const auto d = decode_beacon(encode_beacon(b, o), o);
  ASSERT_TRUE(d);
  EXPECT_FALSE(d->going_home);
  EXPECT_TRUE(d->self.landed);
  EXPECT_EQ(d->round, 6);
  ASSERT_EQ(d->records.size(), 2u);
  EXPECT_TRUE(d->records[0].landed);
  EXPECT_EQ(d->records[0].distance_hops, 127);  // the flag does not eat into the hop count
  EXPECT_FALSE(d->records[1].landed);
  EXPECT_EQ(d->records[1].distance_hops, 3);
  // rounds wrap in 3 bits; the going-home bit stays its own
  b.round = kRounds + 1;
  b.going_home = true;
  const auto w = decode_beacon(encode_beacon(b, o), o);
  ASSERT_TRUE(w);
  EXPECT_EQ(w->round, 1);
  EXPECT_TRUE(w->going_home);
  EXPECT_FALSE(w->homebound);
  // homebound is its own bit too: the round and the other flags stay
  b.homebound = true;
  const auto h = decode_beacon(encode_beacon(b, o), o);
  ASSERT_TRUE(h);
  EXPECT_TRUE(h->homebound);
  EXPECT_EQ(h->round, 1);
  EXPECT_TRUE(h->going_home);
  EXPECT_TRUE(h->self.landed);
}

TEST(RadioMessages, MalformedBeaconsAreRejected) {
  Beacon b;
  b.self.id = 1;
  Frame f = encode_beacon(b, {});
  f.push_back(0);  // length disagrees with the count
  EXPECT_FALSE(decode_beacon(f, {}));
  EXPECT_FALSE(decode_beacon(Frame{1, 2, 3}, {}));
  f = encode_beacon(b, {});
  f[1] = 200;  // id beyond kMaxAgents
  EXPECT_FALSE(decode_beacon(f, {}));
}

TEST(RadioMessages, ACompactMapIsOneFrame) {
  AggregateMessage m;
  m.sender = 4;
  m.origin = 0;
  m.query_id = 9;
  m.version = 3;
  m.responded = 0x1F;
  m.acked = 0x3;
  m.apd = AreaParts(108);
  for (int s = 0; s < 108; ++s) m.apd.add(s, {0.0, 187.5});  // one pass of a 25-agent flock
  for (int s = 0; s < 50; ++s) m.apd.add(s, {300.0, 487.5});
  const auto frames = encode_aggregate(m);
  ASSERT_EQ(frames.size(), 1u);  // two runs: 29 + 2 * 2 + 3 * 4 = 45 bytes
  EXPECT_EQ(frames[0].size(), 45u);
  AggregateReassembler r(108);
  const auto d = r.add(frames[0]);
  ASSERT_TRUE(d);
  EXPECT_EQ(d->apd, m.apd);
  EXPECT_EQ(d->responded, 0x1Fu);
  EXPECT_EQ(d->acked, 0x3u);
  EXPECT_EQ(d->version, 3);
}

TEST(RadioMessages, AFragmentedMapIsReassembledInAnyOrderAndRoundedInwards) {
  AggregateMessage m;
  m.sender = 2;
  m.origin = 1;
  m.query_id = 4;
  m.apd = AreaParts(100);
  // a different interval list in every stripe: no runs, many fragments
  for (int s = 0; s < 100; ++s) m.apd.add(s, {s * 0.21, 50.0 + s * 0.333});
  const auto frames = encode_aggregate(m);
  ASSERT_GT(frames.size(), 3u);
  for (const Frame& f : frames) EXPECT_LE(f.size(), kMaxFrameBytes);
  AggregateReassembler r(100);
  std::optional<AggregateMessage> d;
  for (size_t i = frames.size(); i-- > 0;) {
    auto got = r.add(frames[i]);
    if (i > 0) {
      EXPECT_FALSE(got);
    } else {
      d = got;
    }
  }
  ASSERT_TRUE(d);
  for (int s = 0; s < 100; ++s) {
    ASSERT_EQ(d->apd.stripe(s).size(), 1u);
    const Interval iv = d->apd.stripe(s)[0];
    // start rounded up, end down, to 0.1 m: never more than was covered
    EXPECT_GE(iv.start_m, m.apd.stripe(s)[0].start_m - 1e-9);
    EXPECT_LE(iv.end_m, m.apd.stripe(s)[0].end_m + 1e-9);
    EXPECT_NEAR(iv.start_m, m.apd.stripe(s)[0].start_m, 0.1);
    EXPECT_NEAR(iv.end_m, m.apd.stripe(s)[0].end_m, 0.1);
  }
}

// One agent of 5 over 600 x 600 m after 16 passes: 16 bands (one per pass) in each of the 108
// stripes, every stripe a little different: 108 one-stripe fragments. Up to 64 fragments, the
// stripes past the 64th were dropped, so the leader's map lost them and replanned them for ever.
TEST(RadioMessages, AMapOfOver64FragmentsArrivesWhole) {
  AggregateMessage m;
  m.sender = 3;
  m.apd = AreaParts(108);
  for (int s = 0; s < 108; ++s)
    for (int band = 0; band < 16; ++band) m.apd.add(s, {37.0 * band + 0.1 * s, 37.0 * band + 20.0});
  const auto frames = encode_aggregate(m);
  ASSERT_EQ(frames.size(), 108u);
  AggregateReassembler r(108);
  std::optional<AggregateMessage> d;
  for (const Frame& f : frames) {
    EXPECT_FALSE(d);
    d = r.add(f);
  }
  ASSERT_TRUE(d);
  EXPECT_NEAR(d->apd.covered_fraction(600.0), m.apd.covered_fraction(600.0), 1e-3);
  ASSERT_EQ(d->apd.stripe(107).size(), 16u);
}

TEST(RadioMessages, MalformedFragmentsAreIgnored) {
  AggregateMessage m;
  m.apd = AreaParts(10);
  m.apd.add(0, {0, 5});
  Frame f = encode_aggregate(m)[0];
  AggregateReassembler r(5);  // fewer stripes than the frame claims
  EXPECT_FALSE(r.add(f));
  AggregateReassembler ok(10);
  Frame truncated(f.begin(), f.end() - 1);
  EXPECT_FALSE(ok.add(truncated));
  EXPECT_TRUE(ok.add(f));
}

// The ground-station link's APD (3.6) is one message whatever its size: the same runs as the
// radio's aggregation fragment after a stripe count.
TEST(RadioMessages, AnApdForTheStationIsOneMessageOfRuns) {
  AreaParts apd(108);
  for (int s = 0; s < 108; ++s) apd.add(s, {0.0, 187.5});
  for (int s = 0; s < 50; ++s) apd.add(s, {300.0, 487.5});
  const std::vector<uint8_t> bytes = encode_apd(apd);
  EXPECT_EQ(bytes.size(), 18u);  // 2 + two runs: 2 * 2 + 3 * 4
  const auto d = decode_apd(bytes, 108);
  ASSERT_TRUE(d);
  EXPECT_EQ(*d, apd);
  // a different list in every stripe: 100 runs, still one message, ends rounded inwards
  AreaParts ragged(100);
  for (int s = 0; s < 100; ++s) ragged.add(s, {s * 0.21, 50.0 + s * 0.333});
  const auto r = decode_apd(encode_apd(ragged), 100);
  ASSERT_TRUE(r);
  for (int s = 0; s < 100; ++s) {
    ASSERT_EQ(r->stripe(s).size(), 1u);
    EXPECT_GE(r->stripe(s)[0].start_m, ragged.stripe(s)[0].start_m - 1e-9);
    EXPECT_LE(r->stripe(s)[0].end_m, ragged.stripe(s)[0].end_m + 1e-9);
  }
}

TEST(RadioMessages, MalformedStationApdsAreRefused) {
  AreaParts apd(10);
  apd.add(3, {1.0, 5.0});
  const std::vector<uint8_t> bytes = encode_apd(apd);
  EXPECT_TRUE(decode_apd(bytes, 10));
  EXPECT_FALSE(decode_apd(bytes, 11));  // another rectangle's stripes
  EXPECT_FALSE(decode_apd(std::vector<uint8_t>(bytes.begin(), bytes.end() - 1), 10));
  EXPECT_FALSE(decode_apd({}, 10));
  std::vector<uint8_t> inverted = bytes;
  // the second run (stripe 3) holds [1.0, 5.0) as dm 10, 50: swap its ends
  const size_t at = 2 + 2;  // stripe count, then run 0 (3 stripes, no interval)
  ASSERT_EQ(inverted[at], 1);
  ASSERT_EQ(inverted[at + 1], 1);
  std::swap(inverted[at + 2], inverted[at + 4]);
  EXPECT_FALSE(decode_apd(inverted, 10));
}

}  // namespace
}  // namespace uavsim::missions::coverage
