// The flock's radio frames: beacons and fragmented aggregation messages within 127 bytes, or
// within the channel's smaller frame (116 bytes on the ns3 backend).
#include "radio_messages.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <random>
#include <string>

namespace uavsim::missions::coverage {
namespace {

// 802.15.4's whole frame (the simple channel), and lr-wpan's with its MAC header (the ns3 channel)
const FrameFit k127 = FrameFit{};
constexpr size_t kNs3FrameBytes = 116;
constexpr double kPosQuantTol_m = 0.051;      // half of the 0.1 m step, and a margin
constexpr double kSpeedQuantTol_m_s = 0.051;  // the same for the 0.1 m/s step
constexpr double kHeadingQuantTol_rad = 1e-4;
constexpr double kSpeedTol_m_s = 1e-9;
constexpr double kIntervalTol_m = 0.1;
constexpr double kFractionTol = 1e-3;

TEST(RadioMessages, BeaconRoundTripsWithinAFrame) {
  const RadioFrameOrigin o{100.0, -50.0};
  Beacon b;
  b.self = {3, 65000, 123.45, -40.0, -1.5, 4.9, -0.3, 0, 0};
  b.going_home = true;
  for (int i = 0; i < 9; ++i) b.records.push_back({10 + i, 7, 200.0 + i, 0.0, 3.1, 0, 0, 2, 1500});
  const Frame f = encode_beacon(b, o, k127);
  EXPECT_EQ(f.size(), 14u + 14u * kMaxRecordsPerBeacon);  // 126: at most 8 records
  EXPECT_LE(f.size(), kMaxFrameBytes);
  const auto d = decode_beacon(f, o);
  ASSERT_TRUE(d);
  EXPECT_EQ(d->self.id, 3);
  EXPECT_EQ(d->self.seq, 65000);
  EXPECT_NEAR(d->self.x_m, 123.5, kPosQuantTol_m);  // 0.1 m steps
  EXPECT_NEAR(d->self.y_m, -40.0, kPosQuantTol_m);
  EXPECT_NEAR(d->self.heading_rad, -1.5, kHeadingQuantTol_rad);
  EXPECT_NEAR(d->self.vx_m_s, 4.9, kSpeedTol_m_s);
  EXPECT_NEAR(d->self.vy_m_s, -0.3, kSpeedTol_m_s);
  EXPECT_TRUE(d->going_home);
  ASSERT_EQ(d->records.size(), 8u);
  EXPECT_EQ(d->records[6].id, 16);
  EXPECT_EQ(d->records[6].distance_hops, 2);
  EXPECT_EQ(d->records[6].age_ms, 1500);
  EXPECT_NEAR(d->records[6].heading_rad, 3.1, kHeadingQuantTol_rad);
}

TEST(RadioMessages, BeaconCarriesLandedFlagsAndTheSurveyRound) {
  const RadioFrameOrigin o{0.0, 0.0};
  Beacon b;
  b.self = {5, 9, 1.0, 2.0, 0.0, 0, 0, 0, 0, true};
  b.round = 6;
  AgentRecord far{7, 3, 0.0, 0.0, 0.0, 0, 0, 127, 200, true};
  AgentRecord flying{8, 4, 0.0, 0.0, 0.0, 0, 0, 3, 100, false};
  b.records = {far, flying};
  const auto d = decode_beacon(encode_beacon(b, o, k127), o);
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
  const auto w = decode_beacon(encode_beacon(b, o, k127), o);
  ASSERT_TRUE(w);
  EXPECT_EQ(w->round, 1);
  EXPECT_TRUE(w->going_home);
  EXPECT_FALSE(w->homebound);
  // homebound is its own bit too: the round and the other flags stay
  b.homebound = true;
  const auto h = decode_beacon(encode_beacon(b, o, k127), o);
  ASSERT_TRUE(h);
  EXPECT_TRUE(h->homebound);
  EXPECT_EQ(h->round, 1);
  EXPECT_TRUE(h->going_home);
  EXPECT_TRUE(h->self.landed);
}

TEST(RadioMessages, MalformedBeaconsAreRejected) {
  Beacon b;
  b.self.id = 1;
  Frame f = encode_beacon(b, {}, k127);
  f.push_back(0);  // length disagrees with the count
  EXPECT_FALSE(decode_beacon(f, {}));
  EXPECT_FALSE(decode_beacon(Frame{1, 2, 3}, {}));
  f = encode_beacon(b, {}, k127);
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
  const auto frames = encode_aggregate(m, k127);
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
  const auto frames = encode_aggregate(m, k127);
  ASSERT_GT(frames.size(), 3u);
  for (const Frame& f : frames) EXPECT_LE(f.size(), kMaxFrameBytes);
  AggregateReassembler r(100);
  const AggregateMessage* d = nullptr;
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
    EXPECT_NEAR(iv.start_m, m.apd.stripe(s)[0].start_m, kIntervalTol_m);
    EXPECT_NEAR(iv.end_m, m.apd.stripe(s)[0].end_m, kIntervalTol_m);
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
  const auto frames = encode_aggregate(m, k127);
  ASSERT_EQ(frames.size(), 108u);
  AggregateReassembler r(108);
  const AggregateMessage* d = nullptr;
  for (const Frame& f : frames) {
    EXPECT_FALSE(d);
    d = r.add(f);
  }
  ASSERT_TRUE(d);
  EXPECT_NEAR(d->apd.covered_fraction(600.0), m.apd.covered_fraction(600.0), kFractionTol);
  ASSERT_EQ(d->apd.stripe(107).size(), 16u);
}

// The frame size comes from the channel: 127 bytes carry 8 records a beacon (14 + 8 * 14 = 126),
// 116 carry 7 (112); a channel allowing more than 802.15.4's 127 is used up to 127; one too small
// for a fragment of one interval (29 + 2 + 4 = 35 bytes) is refused with the reason.
TEST(RadioMessages, TheFrameFitFollowsTheChannel) {
  std::string error;
  const auto full = fit_frames(127, &error);
  ASSERT_TRUE(full) << error;
  EXPECT_EQ(full->max_frame_bytes, 127u);
  EXPECT_EQ(full->beacon_records, 8);
  EXPECT_EQ(full->max_frame_bytes, k127.max_frame_bytes);  // the default is the simple channel's
  EXPECT_EQ(full->beacon_records, k127.beacon_records);
  const auto ns3 = fit_frames(kNs3FrameBytes, &error);
  ASSERT_TRUE(ns3) << error;
  EXPECT_EQ(ns3->max_frame_bytes, 116u);
  EXPECT_EQ(ns3->beacon_records, 7);
  // 802.11's 1500 bytes: aggregation fragments of up to 1500, beacons as at 127 (8 records)
  const auto wifi = fit_frames(1500, &error);
  ASSERT_TRUE(wifi) << error;
  EXPECT_EQ(wifi->max_frame_bytes, 1500u);
  EXPECT_EQ(wifi->beacon_records, 8);
  const auto large = fit_frames(2304, &error);
  ASSERT_TRUE(large) << error;
  EXPECT_EQ(large->max_frame_bytes, 1500u);
  EXPECT_EQ(large->beacon_records, 8);
  const auto smallest = fit_frames(kMinFrameBytes, &error);
  ASSERT_TRUE(smallest) << error;
  EXPECT_EQ(smallest->beacon_records, 1);
  for (size_t bytes : {size_t{0}, size_t{1}, size_t{28}, kMinFrameBytes - 1}) {
    error.clear();
    EXPECT_FALSE(fit_frames(bytes, &error)) << bytes;
    EXPECT_NE(error.find("at most " + std::to_string(bytes) + " bytes"), std::string::npos)
        << error;
    EXPECT_NE(error.find("at least 35"), std::string::npos) << error;
  }
}

// A beacon over a full ADB (25 agents) at each size: as many records as fit, the frame within the
// size, and every field of them back as sent, in order.
TEST(RadioMessages, BeaconsFitTheChannelsFrameAndRoundTrip) {
  const RadioFrameOrigin o{10.0, 20.0};
  Beacon b;
  b.self = {2, 77, 50.0, 60.0, 0.5, 3.0, -1.0, 0, 0};
  b.round = 3;
  for (int i = 0; i < 25; ++i)
    b.records.push_back({i, static_cast<uint16_t>(100 + i), 10.0 + i, 20.0 - i, 0.25 * i, 0.1 * i,
                         -0.1 * i, i % 5, 40 * i, i % 2 == 0});
  for (size_t bytes : {kMinFrameBytes, kNs3FrameBytes, kMaxFrameBytes, kMaxAggregateFrameBytes}) {
    SCOPED_TRACE(bytes);
    const FrameFit fit = *fit_frames(bytes, nullptr);
    const Frame f = encode_beacon(b, o, fit);
    EXPECT_LE(f.size(), std::min(bytes, kMaxFrameBytes));
    EXPECT_EQ(f.size(), 14u + 14u * static_cast<size_t>(fit.beacon_records));
    // as many as fit: one more would not
    if (fit.beacon_records < kMaxRecordsPerBeacon) {
      EXPECT_GT(f.size() + 14u, bytes);
    }
    const auto d = decode_beacon(f, o);
    ASSERT_TRUE(d);
    EXPECT_EQ(d->self.id, 2);
    EXPECT_EQ(d->round, 3);
    ASSERT_EQ(d->records.size(), static_cast<size_t>(fit.beacon_records));
    for (size_t i = 0; i < d->records.size(); ++i) {
      const AgentRecord& sent = b.records[i];
      const AgentRecord& got = d->records[i];
      EXPECT_EQ(got.id, sent.id);
      EXPECT_EQ(got.seq, sent.seq);
      EXPECT_NEAR(got.x_m, sent.x_m, kPosQuantTol_m);
      EXPECT_NEAR(got.y_m, sent.y_m, kPosQuantTol_m);
      EXPECT_NEAR(got.heading_rad, sent.heading_rad, kHeadingQuantTol_rad);
      EXPECT_NEAR(got.vx_m_s, sent.vx_m_s, kSpeedQuantTol_m_s);
      EXPECT_NEAR(got.vy_m_s, sent.vy_m_s, kSpeedQuantTol_m_s);
      EXPECT_EQ(got.distance_hops, sent.distance_hops);
      EXPECT_EQ(got.age_ms, sent.age_ms);
      EXPECT_EQ(got.landed, sent.landed);
    }
  }
  // a fit asking for more records than its frame holds still writes no more than fit
  const Frame over = encode_beacon(b, o, FrameFit{kNs3FrameBytes, kMaxRecordsPerBeacon});
  EXPECT_LE(over.size(), kNs3FrameBytes);
}

// Maps on the 0.1 m grid (rounding inwards changes nothing): at 116 and at 127 bytes every fragment
// is within the size, the reassembled map is the map sent (nothing cut), and the fragments use the
// room (116 bytes need at least as many fragments as 127).
TEST(RadioMessages, AggregationFragmentsFitTheChannelsFrameAndNothingIsCut) {
  // ragged: a different list in every stripe; dense: 20 intervals a stripe (under the 21 that one
  // fragment holds at 116 bytes), the same in runs of 3 stripes
  AggregateMessage ragged, dense;
  ragged.sender = dense.sender = 3;
  ragged.apd = AreaParts(100);
  for (int s = 0; s < 100; ++s)
    for (int band = 0; band < 1 + s % 9; ++band)
      ragged.apd.add(s, {(300.0 * band + s) / 10.0, 30.0 * band + 12.5});
  dense.apd = AreaParts(60);
  for (int s = 0; s < 60; ++s)
    for (int band = 0; band < 20; ++band)
      dense.apd.add(s, {(200.0 * band + s / 3) / 10.0, 20.0 * band + 10.0});
  for (const AggregateMessage* m : {&ragged, &dense}) {
    size_t fragments[3] = {0, 0, 0};
    size_t longest[3] = {0, 0, 0};
    int k = 0;
    for (size_t bytes : {kNs3FrameBytes, kMaxFrameBytes, kMaxAggregateFrameBytes}) {
      SCOPED_TRACE(bytes);
      const auto frames = encode_aggregate(*m, *fit_frames(bytes, nullptr));
      fragments[k] = frames.size();
      AggregateReassembler r(m->apd.stripe_count());
      const AggregateMessage* d = nullptr;
      for (const Frame& f : frames) {
        EXPECT_LE(f.size(), bytes);
        longest[k] = std::max(longest[k], f.size());
        EXPECT_FALSE(d);
        d = r.add(f);
      }
      ASSERT_TRUE(d);
      EXPECT_EQ(d->apd, m->apd);
      ++k;
    }
    EXPECT_GE(fragments[0], fragments[1]);
    EXPECT_GT(fragments[1], fragments[2]);  // 1500 bytes: fewer, larger fragments
    // the ragged map's small runs fill a fragment to the end (the dense map's 82-byte runs go one
    // to a fragment at either size)
    if (m == &ragged) {
      EXPECT_GT(longest[1], kNs3FrameBytes);
      EXPECT_GT(fragments[0], fragments[1]);
    }
  }
}

// More intervals in a stripe than a fragment holds (30: 24 fit 127 bytes, 21 fit 116): the extra
// ones are dropped, so the map claims less, never more, and no frame is over the size.
TEST(RadioMessages, AStripeOverAFragmentsIntervalsIsSentShortNeverOver) {
  AggregateMessage m;
  m.apd = AreaParts(4);
  for (int s = 0; s < 4; ++s)
    for (int band = 0; band < 30; ++band) m.apd.add(s, {10.0 * band, 10.0 * band + 5.0});
  for (size_t bytes : {kNs3FrameBytes, kMaxFrameBytes}) {
    SCOPED_TRACE(bytes);
    const auto frames = encode_aggregate(m, *fit_frames(bytes, nullptr));
    AggregateReassembler r(4);
    const AggregateMessage* d = nullptr;
    for (const Frame& f : frames) {
      EXPECT_LE(f.size(), bytes);
      d = r.add(f);
    }
    ASSERT_TRUE(d);
    const size_t fit = (bytes - 31) / 4;
    for (int s = 0; s < 4; ++s) EXPECT_EQ(d->apd.stripe(s).size(), fit);
    EXPECT_LT(d->apd.covered_fraction(300.0), m.apd.covered_fraction(300.0));
  }
}

TEST(RadioMessages, MalformedFragmentsAreIgnored) {
  AggregateMessage m;
  m.apd = AreaParts(10);
  m.apd.add(0, {0, 5});
  Frame f = encode_aggregate(m, k127)[0];
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

// At 1500 bytes a fragment has room for 367 intervals, but a run counts its intervals in a byte:
// 300 intervals in a stripe are sent as 255 (claiming less, never more), in frames within 1500.
TEST(RadioMessages, AStripeOf300IntervalsIsSentAs255In1500ByteFrames) {
  AggregateMessage m;
  m.apd = AreaParts(2);
  for (int s = 0; s < 2; ++s)
    for (int band = 0; band < 300; ++band) m.apd.add(s, {2.0 * band, 2.0 * band + 1.0});
  const auto frames = encode_aggregate(m, *fit_frames(kMaxAggregateFrameBytes, nullptr));
  AggregateReassembler r(2);
  const AggregateMessage* d = nullptr;
  for (const Frame& f : frames) {
    EXPECT_LE(f.size(), kMaxAggregateFrameBytes);
    d = r.add(f);
  }
  ASSERT_TRUE(d);
  for (int s = 0; s < 2; ++s) EXPECT_EQ(d->apd.stripe(s).size(), 255u);
}

// FNV-1a over frames, each preceded by its length: pins the bytes the encoders write.
uint64_t fnv1a(const std::vector<Frame>& frames) {
  uint64_t h = 14695981039346656037ull;
  auto mix = [&h](uint8_t b) {
    h ^= b;
    h *= 1099511628211ull;
  };
  for (const Frame& f : frames) {
    mix(static_cast<uint8_t>(f.size() & 0xFF));
    mix(static_cast<uint8_t>(f.size() >> 8));
    for (uint8_t b : f) mix(b);
  }
  return h;
}

// A map with runs, ragged stripes and a stripe over a fragment's intervals, as the encoders wrote
// it before they kept their runs in one flat list (the bytes must not change: the flock's frames
// and the station's map are the same on either side of that change).
TEST(RadioMessages, TheEncodersWriteTheSameBytesAsBefore) {
  AggregateMessage m;
  m.sender = 7;
  m.origin = 2;
  m.query_id = 513;
  m.version = 9;
  m.responded = 0x1F0F;
  m.acked = 0x30;
  m.apd = AreaParts(40);
  for (int s = 0; s < 40; ++s) m.apd.add(s, {0.0, 187.55});
  for (int s = 5; s < 25; ++s) m.apd.add(s, {200.0 + 0.37 * s, 230.04 + 0.5 * s});
  for (int band = 0; band < 30; ++band) m.apd.add(30, {300.0 + 5.0 * band, 302.5 + 5.0 * band});
  std::vector<uint64_t> got;
  for (size_t bytes : {kNs3FrameBytes, kMaxFrameBytes, kMaxAggregateFrameBytes}) {
    const auto frames = encode_aggregate(m, *fit_frames(bytes, nullptr));
    got.push_back(frames.size());
    got.push_back(fnv1a(frames));
  }
  got.push_back(fnv1a({encode_apd(m.apd)}));
  const std::vector<uint64_t> before{5u,
                                     0x8976759897509cb6ull,
                                     5u,
                                     0x77375bdc4e560ccbull,
                                     1u,
                                     0xff74585e4d53e0c9ull,
                                     0x3428048b462a2f14ull};
  EXPECT_EQ(got, before);
}

// A sender's map as the flock sends it: a band that every stripe shares, and one more band in a
// few stripes, a different one in each (runs of several stripes and of one).
AggregateMessage fragmented_message(int sender, uint16_t version, double band_m) {
  AggregateMessage m;
  m.sender = sender;
  m.origin = 1;
  m.query_id = 4;
  m.version = version;
  m.responded = 0b111;
  m.acked = 0b10;
  m.apd = AreaParts(60);
  for (int s = 0; s < 60; ++s) m.apd.add(s, {0.0, band_m});
  for (int s = 10; s < 40; ++s) m.apd.add(s, {band_m + 10.0 + s, band_m + 30.0 + 2.0 * s});
  return m;
}

// The reassembler gathers every message in memory it reuses (one per sender): what it hands out
// must not depend on what that memory held before.
TEST(RadioMessages, ReassemblyIsTheSameInAnyOrderWithRepeatsAndAfterEarlierMessages) {
  const AggregateMessage first = fragmented_message(3, 1, 100.0);
  const AggregateMessage second = fragmented_message(3, 2, 50.0);  // fewer covered, other stripes
  const auto a = encode_aggregate(first, k127);
  const auto b = encode_aggregate(second, k127);
  ASSERT_GT(a.size(), 3u);
  ASSERT_GT(b.size(), 3u);
  AggregateReassembler r(60);
  // the first message, in reverse with a repeat in between: complete at its last missing fragment
  const AggregateMessage* d = nullptr;
  for (size_t i = a.size(); i-- > 0;) {
    EXPECT_FALSE(d);
    d = r.add(a[i]);
    if (i == a.size() - 2) {
      EXPECT_FALSE(r.add(a[i + 1]));  // a repeat completes nothing
    }
  }
  ASSERT_TRUE(d);
  EXPECT_EQ(d->version, 1);
  const AreaParts first_map = d->apd;
  // the same message again (a retransmission): a new message, complete only once whole again
  EXPECT_FALSE(r.add(a[0]));
  // half of it, then the next version: the half is dropped, the next version stands alone
  for (size_t i = 1; i < a.size() / 2; ++i) EXPECT_FALSE(r.add(a[i]));
  d = nullptr;
  for (size_t i = 0; i < b.size(); ++i) {
    EXPECT_FALSE(d);
    d = r.add(b[i]);
  }
  ASSERT_TRUE(d);
  EXPECT_EQ(d->version, 2);
  EXPECT_EQ(d->responded, 0b111u);
  EXPECT_EQ(d->acked, 0b10u);
  // as a reassembler that never held anything gets it
  AggregateReassembler fresh(60);
  const AggregateMessage* f = nullptr;
  for (const Frame& fr : b) f = fresh.add(fr);
  ASSERT_TRUE(f);
  EXPECT_EQ(d->apd, f->apd);
  EXPECT_FALSE(d->apd == first_map);  // the first map's stripes left nothing behind
  // the first message whole again, after the second: the first map again
  d = nullptr;
  for (const Frame& fr : a) d = r.add(fr);
  ASSERT_TRUE(d);
  EXPECT_EQ(d->apd, first_map);
}

TEST(RadioMessages, ReassemblyKeepsSendersApartAndIgnoresAMalformedFragmentBetween) {
  const AggregateMessage m3 = fragmented_message(3, 1, 100.0);
  const AggregateMessage m9 = fragmented_message(9, 5, 40.0);
  const auto a = encode_aggregate(m3, k127);
  const auto b = encode_aggregate(m9, k127);
  AggregateReassembler r(60);
  const AggregateMessage* d3 = nullptr;
  const AggregateMessage* d9 = nullptr;
  for (size_t i = 0; i < std::max(a.size(), b.size()); ++i) {
    if (i < a.size() && !d3) d3 = r.add(a[i]);
    Frame bad = a[0];
    bad.pop_back();  // a run cut short
    EXPECT_FALSE(r.add(bad));
    if (i < b.size()) d9 = r.add(b[i]);
  }
  ASSERT_TRUE(d9);
  EXPECT_EQ(d9->sender, 9);
  AggregateReassembler alone(60);
  const AggregateMessage* e9 = nullptr;
  for (const Frame& f : b) e9 = alone.add(f);
  ASSERT_TRUE(e9);
  EXPECT_EQ(d9->apd, e9->apd);
  EXPECT_EQ(d9->version, 5);
}

// The reassembler gathers each sender's messages in the same memory: a stream of fragments from
// several senders, versions interleaved, stripe ranges overlapping within a message (fragments of
// different maps relabelled into one), fragments repeated. Each message it hands out must be the
// one a fresh reassembler makes of that message's fragments alone.
TEST(RadioMessages, ReassemblyDoesNotDependOnEarlierMessagesOfTheSender) {
  std::vector<Frame> pool;
  for (double band : {100.0, 50.0, 80.0}) {
    for (const Frame& f : encode_aggregate(fragmented_message(3, 1, band), k127)) pool.push_back(f);
  }
  AreaParts sparse(60);  // one short run: a fragment of few bytes
  sparse.add(7, {1.0, 2.0});
  AggregateMessage m = fragmented_message(3, 1, 10.0);
  m.apd = sparse;
  for (const Frame& f : encode_aggregate(m, k127)) pool.push_back(f);
  std::mt19937 rng(17);
  AggregateReassembler r(60);
  std::map<int, std::vector<Frame>> since_start;  // per sender: the message's fragments so far
  std::map<int, Frame> last;                      // per sender: the last fragment (its header)
  int completed = 0;
  for (int step = 0; step < 4000; ++step) {
    Frame f = pool[rng() % pool.size()];
    const int sender = rng() % 2 == 0 ? 3 : 9;
    f[1] = static_cast<uint8_t>(sender);
    f[5] = static_cast<uint8_t>(1 + rng() % 2);  // version 1 or 2
    f[6] = 0;
    f[8] = 3;  // fragments
    f[7] = static_cast<uint8_t>(rng() % 3);
    // the same message as the last fragment of this sender (origin, query, version, fragments)?
    auto& frames = since_start[sender];
    const auto it = last.find(sender);
    if (it == last.end() || !std::equal(f.begin() + 2, f.begin() + 7, it->second.begin() + 2) ||
        f[8] != it->second[8]) {
      frames.clear();
    }
    frames.push_back(f);
    last[sender] = f;
    const AggregateMessage* d = r.add(f);
    if (!d) continue;
    ++completed;
    AggregateReassembler fresh(60);
    const AggregateMessage* want = nullptr;
    for (const Frame& g : frames) want = fresh.add(g);
    ASSERT_TRUE(want) << step;
    ASSERT_EQ(d->apd, want->apd) << step;
    ASSERT_EQ(d->sender, want->sender);
    ASSERT_EQ(d->version, want->version);
    ASSERT_EQ(d->responded, want->responded);
    ASSERT_EQ(d->acked, want->acked);
    frames.clear();
    last.erase(sender);  // complete: the next fragment starts a message
  }
  EXPECT_GT(completed, 200);
}

// Every byte string cut short is refused, wherever the cut falls (in a run's header, between an
// interval's ends, between intervals), and refusing it leaves the next message whole.
TEST(RadioMessages, EveryCutOfAFragmentOrStationMapIsRefused) {
  const AggregateMessage m = fragmented_message(5, 2, 80.0);
  const std::vector<uint8_t> apd = encode_apd(m.apd);
  for (size_t len = 0; len < apd.size(); ++len) {
    EXPECT_FALSE(decode_apd(std::vector<uint8_t>(apd.begin(), apd.begin() + len), 60)) << len;
  }
  ASSERT_TRUE(decode_apd(apd, 60));
  const auto frames = encode_aggregate(m, k127);
  AggregateReassembler r(60);
  for (size_t k = 0; k < frames.size(); ++k) {
    for (size_t len = 0; len < frames[k].size(); ++len)
      EXPECT_FALSE(r.add(Frame(frames[k].begin(), frames[k].begin() + len))) << k << " " << len;
  }
  const AggregateMessage* d = nullptr;
  for (const Frame& f : frames) d = r.add(f);
  ASSERT_TRUE(d);
  EXPECT_EQ(d->apd, *decode_apd(apd, 60));
}

// The beacon decoder that fills a caller's Beacon leaves nothing of the last one behind.
TEST(RadioMessages, ABeaconDecodedIntoAUsedBeaconIsTheSameAsFresh) {
  const RadioFrameOrigin o{10.0, 20.0};
  Beacon many;
  many.self = {4, 11, 30.0, 40.0, 0.5, 1.0, -1.0, 3, 700, true};
  many.going_home = true;
  many.homebound = true;
  many.round = 3;
  for (int i = 0; i < 8; ++i) many.records.push_back({10 + i, 7, 1.0 * i, 2.0, 0.1, 0, 0, 2, 100});
  Beacon few;
  few.self = {6, 12, 50.0, 60.0, -0.5, 0.0, 0.0, 0, 0, false};
  few.records.push_back({20, 9, 5.0, 6.0, 0.2, 0, 0, 1, 50});
  Beacon used;
  ASSERT_TRUE(decode_beacon(encode_beacon(many, o, k127), o, &used));
  EXPECT_FALSE(decode_beacon(Frame{1, 2, 3}, o, &used));
  ASSERT_TRUE(decode_beacon(encode_beacon(few, o, k127), o, &used));
  const auto fresh = decode_beacon(encode_beacon(few, o, k127), o);
  ASSERT_TRUE(fresh);
  EXPECT_EQ(used.self.id, 6);
  EXPECT_EQ(used.self.distance_hops, fresh->self.distance_hops);
  EXPECT_EQ(used.self.age_ms, fresh->self.age_ms);
  EXPECT_EQ(used.self.landed, fresh->self.landed);
  EXPECT_EQ(used.going_home, fresh->going_home);
  EXPECT_EQ(used.homebound, fresh->homebound);
  EXPECT_EQ(used.round, fresh->round);
  ASSERT_EQ(used.records.size(), 1u);
  EXPECT_EQ(used.records[0].id, 20);
  EXPECT_EQ(used.records[0].x_m, fresh->records[0].x_m);
}

}  // namespace
}  // namespace uavsim::missions::coverage
