// The shared-memory stream's ring and tick records (common/shm_ring.hpp) on plain memory: records
// round-trip across the wrap, a full ring refuses, and each side refuses what the other may not
// write.
#include "uavsim/common/shm_ring.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <span>
#include <string>
#include <vector>

namespace uavsim::common::shm {
namespace {

constexpr std::size_t kCapacity = kMinCapacity;

struct Region {
  std::vector<std::uint64_t> words = std::vector<std::uint64_t>(region_bytes(kCapacity) / 8);
  void* data() { return words.data(); }
  RingHeader* header() { return static_cast<RingHeader*>(data()); }
};

std::optional<RingError> write_bytes(RingWriter& w, RecordType type,
                                     const std::vector<std::uint8_t>& bytes, std::string* why) {
  const std::span<const std::uint8_t> part(bytes);
  return w.write(type, std::span<const std::span<const std::uint8_t>>(&part, 1), why);
}

std::vector<std::uint8_t> pattern(std::size_t n, std::uint8_t seed) {
  std::vector<std::uint8_t> v(n);
  for (std::size_t i = 0; i < n; ++i) v[i] = static_cast<std::uint8_t>(seed + i * 7);
  return v;
}

TEST(ShmRing, RegionSizeOnlyForPowersOfTwoInRange) {
  EXPECT_EQ(region_bytes(kMinCapacity), kHeaderBytes + kMinCapacity);
  EXPECT_EQ(region_bytes(kMaxCapacity), kHeaderBytes + kMaxCapacity);
  EXPECT_EQ(region_bytes(kMinCapacity / 2), 0u);
  EXPECT_EQ(region_bytes(kMaxCapacity * 2), 0u);
  EXPECT_EQ(region_bytes(kMinCapacity + 8), 0u);
  EXPECT_EQ(region_bytes(0), 0u);
}

TEST(ShmRing, RecordsRoundTripInOrderAcrossTheWrap) {
  Region r;
  RingWriter w(r.data(), kCapacity);
  std::string why;
  auto reader = RingReader::attach(r.data(), region_bytes(kCapacity), &why);
  ASSERT_TRUE(reader) << why;
  // 1000-byte records: 66 fill a 64 KiB ring once, so 300 of them wrap it four times, some records
  // split across the end
  RingReader::Record rec;
  for (int k = 0; k < 300; ++k) {
    const auto bytes =
        pattern(1000 + static_cast<std::size_t>(k % 5), static_cast<std::uint8_t>(k));
    ASSERT_EQ(write_bytes(w, k % 2 ? RecordType::kTick : RecordType::kStream, bytes, &why),
              std::nullopt)
        << k;
    ASSERT_EQ(reader->next(&rec, &why), RingReader::Status::kRecord) << k << why;
    EXPECT_EQ(rec.type, k % 2 ? RecordType::kTick : RecordType::kStream);
    EXPECT_EQ(rec.payload, bytes) << k;
  }
  EXPECT_EQ(reader->next(&rec, &why), RingReader::Status::kEmpty);
  EXPECT_EQ(w.waiting_bytes(), 0u);
}

TEST(ShmRing, AFullRingRefusesUntilTheReaderTakesARecord) {
  Region r;
  RingWriter w(r.data(), kCapacity);
  std::string why;
  auto reader = RingReader::attach(r.data(), region_bytes(kCapacity), &why);
  ASSERT_TRUE(reader);
  // 8-byte frame + 4088 bytes = 4 KiB a record: 16 fill the ring
  const auto bytes = pattern(4088, 1);
  for (int k = 0; k < 16; ++k)
    ASSERT_EQ(write_bytes(w, RecordType::kStream, bytes, &why), std::nullopt) << k;
  EXPECT_EQ(write_bytes(w, RecordType::kStream, bytes, &why), RingError::kFull);
  RingReader::Record rec;
  ASSERT_EQ(reader->next(&rec, &why), RingReader::Status::kRecord);
  EXPECT_EQ(write_bytes(w, RecordType::kStream, bytes, &why), std::nullopt);
  EXPECT_EQ(write_bytes(w, RecordType::kStream, pattern(kCapacity, 2), &why), RingError::kTooLarge);
}

TEST(ShmRing, OneWakeUpUntilTheReaderArmsAgain) {
  Region r;
  RingWriter w(r.data(), kCapacity);
  std::string why;
  auto reader = RingReader::attach(r.data(), region_bytes(kCapacity), &why);
  ASSERT_TRUE(reader);
  EXPECT_TRUE(w.take_wakeup());
  EXPECT_FALSE(w.take_wakeup());  // one is in flight
  reader->arm();
  EXPECT_TRUE(w.take_wakeup());
}

TEST(ShmRing, TheWriterRefusesAReaderPositionOutsideWhatWasWritten) {
  Region r;
  RingWriter w(r.data(), kCapacity);
  std::string why;
  ASSERT_EQ(write_bytes(w, RecordType::kStream, pattern(100, 0), &why), std::nullopt);
  // past the head (a hostile or broken client)
  r.header()->tail = 4096;
  EXPECT_EQ(write_bytes(w, RecordType::kStream, pattern(100, 0), &why), RingError::kCorrupt);
  EXPECT_NE(why.find("outside"), std::string::npos) << why;
  // backwards, after the writer had seen it further on
  r.header()->tail = 112;  // the first record consumed
  ASSERT_EQ(write_bytes(w, RecordType::kStream, pattern(100, 0), &why), std::nullopt);
  r.header()->tail = 0;
  EXPECT_EQ(write_bytes(w, RecordType::kStream, pattern(100, 0), &why), RingError::kCorrupt);
}

TEST(ShmRing, TheReaderRefusesAForeignOrBrokenRing) {
  Region r;
  RingWriter w(r.data(), kCapacity);
  std::string why;
  EXPECT_FALSE(RingReader::attach(r.data(), kHeaderBytes, &why));  // its capacity does not fit
  r.header()->version = 2;
  EXPECT_FALSE(RingReader::attach(r.data(), region_bytes(kCapacity), &why));
  r.header()->version = kVersion;
  r.header()->magic = 0;
  EXPECT_FALSE(RingReader::attach(r.data(), region_bytes(kCapacity), &why));
  r.header()->magic = kMagic;
  r.header()->capacity = kCapacity + 1;
  EXPECT_FALSE(RingReader::attach(r.data(), region_bytes(kCapacity), &why));
  r.header()->capacity = kCapacity;
  ASSERT_TRUE(RingReader::attach(r.data(), region_bytes(kCapacity), &why)) << why;
}

TEST(ShmRing, TheReaderRefusesEveryBrokenRecordField) {
  std::string why;
  RingReader::Record rec;
  auto broken = [&](auto&& breaker) {
    Region r;
    RingWriter w(r.data(), kCapacity);
    EXPECT_EQ(write_bytes(w, RecordType::kStream, pattern(100, 0), &why), std::nullopt);
    auto reader = RingReader::attach(r.data(), region_bytes(kCapacity), &why);
    EXPECT_TRUE(reader);
    std::uint8_t* frame = static_cast<std::uint8_t*>(r.data()) + kHeaderBytes;
    breaker(r, frame);
    return reader->next(&rec, &why);
  };
  EXPECT_EQ(broken([](Region&, std::uint8_t*) {}), RingReader::Status::kRecord);
  // a length past what was written
  EXPECT_EQ(broken([](Region&, std::uint8_t* f) { f[1] = 1; }), RingReader::Status::kCorrupt);
  // an unknown type, another version
  EXPECT_EQ(broken([](Region&, std::uint8_t* f) { f[4] = 9; }), RingReader::Status::kCorrupt);
  EXPECT_EQ(broken([](Region&, std::uint8_t* f) { f[6] = 2; }), RingReader::Status::kCorrupt);
  // a head more than a ring ahead, or not on a record boundary
  EXPECT_EQ(broken([](Region& r, std::uint8_t*) { r.header()->head = kCapacity + 8; }),
            RingReader::Status::kCorrupt);
  EXPECT_EQ(broken([](Region& r, std::uint8_t*) { r.header()->head = 5; }),
            RingReader::Status::kCorrupt);
}

std::vector<std::uint8_t> tick_record(std::uint32_t frames, std::int64_t tick = 3,
                                      double time_s = 0.06) {
  std::vector<std::uint8_t> out = encode_tick_head(tick, time_s, frames);
  for (std::uint32_t k = 0; k < frames; ++k) {
    encode_radio_frame(k + 1, k, 100 + k, k % 2 == 0, 0.05 + k, 0.04 + k, pattern(10 + k, 3), &out);
  }
  return out;
}

TEST(ShmTickRecord, RoundTripsTickTimeAndEveryFrameField) {
  std::string why;
  const auto r = decode_tick(tick_record(3), &why);
  ASSERT_TRUE(r) << why;
  EXPECT_EQ(r->tick, 3);
  EXPECT_EQ(r->time_s, 0.06);
  ASSERT_EQ(r->frames.size(), 3u);
  for (std::uint32_t k = 0; k < 3; ++k) {
    const RadioFrame& f = r->frames[k];
    EXPECT_EQ(f.to, k + 1);
    EXPECT_EQ(f.from, k);
    EXPECT_EQ(f.seq, 100 + k);
    EXPECT_EQ(f.broadcast, k % 2 == 0);
    EXPECT_EQ(f.time_s, 0.05 + k);
    EXPECT_EQ(f.sent_time_s, 0.04 + k);
    EXPECT_EQ(f.data, pattern(10 + k, 3));
  }
  EXPECT_TRUE(decode_tick(tick_record(0), &why)) << why;
}

// Decoding into a record of an earlier tick leaves nothing of it: fewer frames, shorter ones.
TEST(ShmTickRecord, DecodingIntoAnEarlierTicksRecordLeavesNothingOfIt) {
  std::string why;
  TickRecord reused;
  ASSERT_TRUE(decode_tick(tick_record(3, 3), &reused, &why)) << why;
  std::vector<std::uint8_t> later = encode_tick_head(4, 0.08, 1);
  encode_radio_frame(2, 1, 7, false, 0.07, 0.065, pattern(2, 9), &later);
  ASSERT_TRUE(decode_tick(later, &reused, &why)) << why;
  const auto fresh = decode_tick(later, &why);
  ASSERT_TRUE(fresh) << why;
  EXPECT_EQ(reused.tick, 4);
  EXPECT_EQ(reused.time_s, 0.08);
  ASSERT_EQ(reused.frames.size(), 1u);
  EXPECT_EQ(reused.frames[0].to, fresh->frames[0].to);
  EXPECT_EQ(reused.frames[0].seq, 7u);
  EXPECT_EQ(reused.frames[0].data, pattern(2, 9));
}

TEST(ShmTickRecord, RefusesEveryTruncationAndEveryFieldOutOfRange) {
  std::string why;
  const auto good = tick_record(2);
  // every proper prefix is cut short somewhere; one byte more is left over
  for (std::size_t n = 0; n < good.size(); ++n) {
    EXPECT_FALSE(decode_tick(std::span(good.data(), n), &why)) << n;
  }
  auto longer = good;
  longer.push_back(0);
  EXPECT_FALSE(decode_tick(longer, &why));
  // a frame count that the bytes cannot hold
  auto lie = good;
  const std::uint32_t many = 1000;
  std::memcpy(lie.data() + 16, &many, 4);
  EXPECT_FALSE(decode_tick(lie, &why));
  // the head: a negative tick, a time that is not finite
  EXPECT_FALSE(decode_tick(tick_record(1, -1), &why));
  EXPECT_FALSE(decode_tick(tick_record(1, 1, std::nan("")), &why));
  // a frame's fields: receiver, broadcast flag, time, length 0 or over 127
  const std::size_t frame = 20;  // after the head
  auto set = [&](std::size_t offset, auto value) {
    auto bad = tick_record(1);
    std::memcpy(bad.data() + frame + offset, &value, sizeof(value));
    return decode_tick(bad, &why).has_value();
  };
  EXPECT_FALSE(set(0, kMaxVehicleIndex));
  EXPECT_FALSE(set(4, kMaxVehicleIndex));
  EXPECT_FALSE(set(16, std::uint8_t{2}));
  EXPECT_FALSE(set(17, std::numeric_limits<double>::infinity()));
  EXPECT_FALSE(set(25, std::nan("")));
  EXPECT_FALSE(set(33, std::uint16_t{0}));
  EXPECT_FALSE(set(33, std::uint16_t{128}));
  EXPECT_TRUE(set(16, std::uint8_t{1}));  // (the offsets are the fields': a valid value passes)
}

}  // namespace
}  // namespace uavsim::common::shm
