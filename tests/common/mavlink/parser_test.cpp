#include "uavsim/common/mavlink/parser.hpp"

#include <gtest/gtest.h>

#include <random>

#include "uavsim/common/mavlink/codec.hpp"
#include "uavsim/common/mavlink/crc.hpp"
#include "uavsim/common/mavlink/generated/messages.hpp"
#include "test_util.hpp"

namespace uavsim::common::mavlink {
namespace {

constexpr std::uint32_t kSeed = 20261121;

// v2 HEARTBEAT from the reference vectors: no 0xFD/0xFE inside, so a corrupted copy cannot hide a
// false start
const std::vector<std::uint8_t> kHeartbeat =
    test::from_hex("fd090000000101000000000000000203510303e292");
const std::vector<std::uint8_t> kHeartbeatV1 = test::from_hex("fe09000101000000000002035103037851");

struct Collected {
  std::vector<std::vector<std::uint8_t>> raws;
  std::vector<Version> versions;
};

Collected feed_all(Parser& parser, std::span<const std::uint8_t> bytes, std::size_t chunk = 0) {
  Collected c;
  auto on_frame = [&](const Frame& f) {
    c.raws.emplace_back(f.raw.begin(), f.raw.end());
    c.versions.push_back(f.version);
  };
  if (chunk == 0) {
    parser.feed(bytes, on_frame);
  } else {
    for (std::size_t i = 0; i < bytes.size(); i += chunk) {
      parser.feed(bytes.subspan(i, std::min(chunk, bytes.size() - i)), on_frame);
    }
  }
  return c;
}

std::vector<std::uint8_t> concat(std::initializer_list<std::vector<std::uint8_t>> parts) {
  std::vector<std::uint8_t> out;
  for (const auto& p : parts) out.insert(out.end(), p.begin(), p.end());
  return out;
}

// a v2 frame with a correct checksum for the given crc_extra
std::vector<std::uint8_t> make_v2(std::uint32_t msgid, std::vector<std::uint8_t> payload,
                                  std::uint8_t crc_extra, std::uint8_t incompat = 0) {
  std::vector<std::uint8_t> f(kHeaderLenV2 + payload.size());
  f[0] = kStxV2;
  f[1] = static_cast<std::uint8_t>(payload.size());
  f[2] = incompat;
  f[5] = 1;  // sysid
  f[6] = 1;  // compid
  f[7] = static_cast<std::uint8_t>(msgid);
  f[8] = static_cast<std::uint8_t>(msgid >> 8);
  f[9] = static_cast<std::uint8_t>(msgid >> 16);
  std::copy(payload.begin(), payload.end(), f.begin() + kHeaderLenV2);
  std::uint16_t crc = crc_accumulate(std::span<const std::uint8_t>(f).subspan(1), kCrcInit);
  crc = crc_accumulate(crc_extra, crc);
  f.push_back(static_cast<std::uint8_t>(crc));
  f.push_back(static_cast<std::uint8_t>(crc >> 8));
  return f;
}

TEST(Parser, ByteAtATimeFindsTheSameFramesAsOneChunk) {
  std::vector<std::uint8_t> stream;
  for (const auto& v : test::load_vectors())
    stream.insert(stream.end(), v.bytes.begin(), v.bytes.end());
  Parser whole;
  Parser bytewise;
  const Collected a = feed_all(whole, stream);
  const Collected b = feed_all(bytewise, stream, 1);
  EXPECT_EQ(a.raws.size(), 12u);
  EXPECT_EQ(a.raws, b.raws);
  EXPECT_EQ(whole.stats().bytes_dropped, 0u);
  EXPECT_EQ(bytewise.stats().bytes_dropped, 0u);
}

TEST(Parser, ReportsTheVersionOfEachFrame) {
  Parser parser;
  const Collected c = feed_all(parser, concat({kHeartbeatV1, kHeartbeat}));
  ASSERT_EQ(c.versions.size(), 2u);
  EXPECT_EQ(c.versions[0], Version::kV1);
  EXPECT_EQ(c.versions[1], Version::kV2);
}

TEST(Parser, FindsEveryFrameBetweenRandomGarbage) {
  std::mt19937 rng(kSeed);
  std::uniform_int_distribution<int> byte(0, 255);
  std::uniform_int_distribution<int> garbage_len(0, 300);
  // garbage rich in start bytes, so false starts swallow the beginning of real frames
  auto garbage_byte = [&] {
    const int r = byte(rng);
    return static_cast<std::uint8_t>(r < 16 ? kStxV2 : r < 32 ? kStxV1 : byte(rng));
  };

  // a mix of message types, versions, truncated payloads and signed frames
  std::vector<std::vector<std::uint8_t>> frames;
  for (int i = 0; i < 400; ++i) {
    FrameHeader h;
    h.seq = static_cast<std::uint8_t>(i);
    h.version = (i % 5 == 0) ? Version::kV1 : Version::kV2;
    if (i % 7 == 3) h.signing = SigningParams{test::reference_key(), 0, 1000u + i};
    if (h.version == Version::kV1) h.signing.reset();
    EncodedFrame f;
    switch (i % 4) {
      case 0: {
        msg::GlobalPositionInt m;
        m.lat = static_cast<std::int32_t>(rng());
        m.lon = static_cast<std::int32_t>(rng());
        m.hdg = static_cast<std::uint16_t>(i);
        f = encode(h, m);
        break;
      }
      case 1: {
        msg::Heartbeat m;
        m.custom_mode = rng() % 28;
        f = encode(h, m);
        break;
      }
      case 2: {
        msg::Statustext m;
        set_string(m.text, "frame " + std::to_string(i));
        f = encode(h, m);
        break;
      }
      default: {
        msg::CommandLong m;
        m.command = 400;
        m.param1 = static_cast<float>(i);
        f = encode(h, m);
        break;
      }
    }
    ASSERT_FALSE(f.empty());
    frames.emplace_back(f.view().begin(), f.view().end());
  }

  std::vector<std::uint8_t> stream;
  std::size_t garbage_total = 0;
  for (const auto& f : frames) {
    const int n = garbage_len(rng);
    for (int k = 0; k < n; ++k) stream.push_back(garbage_byte());
    garbage_total += n;
    stream.insert(stream.end(), f.begin(), f.end());
  }

  // random chunk sizes, as a socket would deliver them
  Parser parser;
  Collected c;
  std::uniform_int_distribution<std::size_t> chunk_len(1, 700);
  for (std::size_t i = 0; i < stream.size();) {
    const std::size_t n = std::min(chunk_len(rng), stream.size() - i);
    const Collected part = feed_all(parser, std::span<const std::uint8_t>(stream).subspan(i, n));
    c.raws.insert(c.raws.end(), part.raws.begin(), part.raws.end());
    i += n;
  }

  EXPECT_EQ(c.raws, frames);
  EXPECT_EQ(parser.stats().frames, frames.size());
  // every byte is accounted for: in a frame, dropped, or buffered
  EXPECT_EQ(parser.stats().bytes_dropped + parser.buffered(), garbage_total);
  EXPECT_GT(parser.stats().bad_crc + parser.stats().bad_length + parser.stats().unknown_msgid +
                parser.stats().bad_incompat_flags,
            0u);
}

TEST(Parser, CountsBadCrcAndResyncs) {
  std::vector<std::uint8_t> bad = kHeartbeat;
  bad.back() ^= 0xFF;
  Parser parser;
  const Collected c = feed_all(parser, concat({kHeartbeat, bad, kHeartbeat}));
  EXPECT_EQ(c.raws.size(), 2u);
  EXPECT_EQ(parser.stats().bad_crc, 1u);
  EXPECT_EQ(parser.stats().bytes_dropped, bad.size());
}

TEST(Parser, TruncatedFrameDoesNotHideTheNextOne) {
  const std::vector<std::uint8_t> cut(kHeartbeat.begin(), kHeartbeat.begin() + 15);
  Parser parser;
  const Collected c = feed_all(parser, concat({cut, kHeartbeat, kHeartbeat}));
  EXPECT_EQ(c.raws.size(), 2u);
  // the cut frame borrows the next frame's bytes, fails its checksum, and the search restarts
  // inside it
  EXPECT_EQ(parser.stats().bad_crc, 1u);
  EXPECT_EQ(parser.stats().bytes_dropped, cut.size());
}

TEST(Parser, CountsUnknownMessageIdAndSkipsIt) {
  const auto unknown = make_v2(0xABCDEF, {1, 2, 3}, 0);
  Parser parser;
  const Collected c = feed_all(parser, concat({unknown, kHeartbeat}));
  EXPECT_EQ(c.raws.size(), 1u);
  EXPECT_EQ(parser.stats().unknown_msgid, 1u);
  EXPECT_EQ(parser.stats().bytes_dropped, unknown.size());
}

TEST(Parser, CountsUnsupportedIncompatFlags) {
  const auto flagged =
      make_v2(msg::Heartbeat::kId, {0, 0, 0, 0, 2, 3, 0x51, 3, 3}, msg::Heartbeat::kCrcExtra, 0x02);
  Parser parser;
  const Collected c = feed_all(parser, concat({flagged, kHeartbeat}));
  EXPECT_EQ(c.raws.size(), 1u);
  EXPECT_EQ(parser.stats().bad_incompat_flags, 1u);
}

TEST(Parser, CountsBogusLengths) {
  // v2 longer than the message can be, v1 other than the base length
  const auto too_long =
      make_v2(msg::Heartbeat::kId, std::vector<std::uint8_t>(40, 1), msg::Heartbeat::kCrcExtra);
  std::vector<std::uint8_t> short_v1 = {kStxV1, 8, 0, 1, 1, msg::Heartbeat::kId, 1, 1, 1, 1, 1,
                                        1,      1, 1, 0, 0};
  Parser parser;
  const Collected c = feed_all(parser, concat({too_long, kHeartbeat, short_v1, kHeartbeatV1}));
  EXPECT_EQ(c.raws.size(), 2u);
  EXPECT_EQ(parser.stats().bad_length, 2u);
}

TEST(Parser, HoldsAPartialFrameUntilTheRestArrives) {
  Parser parser;
  const std::span<const std::uint8_t> all(kHeartbeat);
  EXPECT_TRUE(feed_all(parser, all.first(7)).raws.empty());
  EXPECT_EQ(parser.buffered(), 7u);
  EXPECT_EQ(feed_all(parser, all.subspan(7)).raws.size(), 1u);
  EXPECT_EQ(parser.buffered(), 0u);

  EXPECT_TRUE(feed_all(parser, all.first(12)).raws.empty());
  parser.reset();
  EXPECT_EQ(parser.buffered(), 0u);
  EXPECT_EQ(parser.stats().bytes_dropped, 12u);
}

TEST(Parser, ParseConsumesUpToTheEndOfOneFrame) {
  const auto two = concat({kHeartbeat, kHeartbeat});
  Parser parser;
  const Frame* frame = nullptr;
  const std::size_t used = parser.parse(two, &frame);
  ASSERT_NE(frame, nullptr);
  EXPECT_EQ(used, kHeartbeat.size());
  EXPECT_EQ(frame->info->name, std::string_view("HEARTBEAT"));
}

}  // namespace
}  // namespace uavsim::common::mavlink
