#include "uavsim/common/mavlink/codec.hpp"

#include <gtest/gtest.h>

#include "uavsim/common/mavlink/crc.hpp"
#include "uavsim/common/mavlink/parser.hpp"
#include "uavsim/common/mavlink/signing.hpp"
#include "uavsim/common/mavlink/wire.hpp"
#include "uavsim/common/mavlink/generated/enums.hpp"
#include "uavsim/common/mavlink/generated/messages.hpp"
#include "test_util.hpp"

namespace uavsim::common::mavlink {
namespace {

std::vector<Frame> parse_all(std::span<const std::uint8_t> bytes, Parser& parser) {
  std::vector<Frame> frames;
  parser.feed(bytes, [&](const Frame& f) { frames.push_back(f); });
  return frames;
}

TEST(Codec, EveryReferenceFrameDecodesAndReencodesByteIdentically) {
  const auto vectors = test::load_vectors();
  ASSERT_EQ(vectors.size(), 12u);
  for (const auto& v : vectors) {
    Parser parser;
    Frame frame;
    int count = 0;
    parser.feed(v.bytes, [&](const Frame& f) {
      frame = f;
      EXPECT_EQ(test::to_hex(f.raw), test::to_hex(v.bytes)) << v.label;
      ++count;
    });
    ASSERT_EQ(count, 1) << v.label;
    EXPECT_EQ(parser.stats().bytes_dropped, 0u) << v.label;
    EXPECT_EQ(frame.version, v.label.starts_with("v1_") ? Version::kV1 : Version::kV2) << v.label;
    EXPECT_EQ(frame.signature.has_value(), v.label.starts_with("v2signed")) << v.label;
    const EncodedFrame again = test::reencode(frame);
    ASSERT_FALSE(again.empty()) << v.label;
    EXPECT_EQ(test::to_hex(again.view()), test::to_hex(v.bytes)) << v.label;
  }
}

TEST(Codec, ReferenceFramesCarryTheLabelledValues) {
  const auto vectors = test::load_vectors();
  auto frame_of = [&](std::string_view prefix) {
    for (const auto& v : vectors) {
      if (v.label.starts_with(prefix)) {
        Parser p;
        auto frames = parse_all(v.bytes, p);
        if (frames.size() == 1) return frames[0];
      }
    }
    ADD_FAILURE() << "no vector " << prefix;
    return Frame{};
  };

  const auto hb = decode<msg::Heartbeat>(frame_of("v2_HEARTBEAT_sys1_comp1_seq1_hexa"));
  ASSERT_TRUE(hb);
  EXPECT_EQ(hb->type, to_underlying(MavType::Hexarotor));
  EXPECT_EQ(hb->base_mode, 217);
  EXPECT_EQ(hb->custom_mode, 4u);
  EXPECT_EQ(hb->system_status, to_underlying(MavState::Active));

  const auto takeoff =
      decode<msg::CommandLong>(frame_of("v2_COMMAND_LONG_sys255_comp190_seq3_takeoff"));
  ASSERT_TRUE(takeoff);
  EXPECT_EQ(takeoff->command, to_underlying(MavCmd::NavTakeoff));
  EXPECT_EQ(takeoff->param7, 10.0f);

  const auto param = decode<msg::ParamValue>(frame_of("v2_PARAM_VALUE"));
  ASSERT_TRUE(param);
  EXPECT_EQ(get_string(param->param_id), "SYSID_THISMAV");
  EXPECT_EQ(param->param_count, 1000);
  EXPECT_EQ(param->param_index, 5);

  const auto text = decode<msg::Statustext>(frame_of("v2_STATUSTEXT"));
  ASSERT_TRUE(text);
  EXPECT_EQ(get_string(text->text), "ArduCopter V4.x");

  // v1 carries no extensions: they decode as zero
  const Frame v1_ack = frame_of("v1_COMMAND_ACK");
  EXPECT_EQ(v1_ack.version, Version::kV1);
  const auto ack = decode<msg::CommandAck>(v1_ack);
  ASSERT_TRUE(ack);
  EXPECT_EQ(ack->command, 400);
  EXPECT_EQ(ack->target_system, 0);

  EXPECT_FALSE(decode<msg::Heartbeat>(v1_ack).has_value());
}

TEST(Codec, V2StripsTrailingZerosAndReceiverZeroFills) {
  msg::GlobalPositionInt pos;
  pos.time_boot_ms = 1234;
  pos.lat = 473977420;
  pos.lon = 85455940;
  // alt .. hdg left at zero: the last non-zero byte is in lon at offset 8..11
  const EncodedFrame f = encode(FrameHeader{}, pos);
  ASSERT_FALSE(f.empty());
  EXPECT_EQ(f.bytes[1], 12);  // payload length on the wire
  EXPECT_EQ(f.size, kHeaderLenV2 + 12 + kChecksumLen);

  Parser parser;
  auto frames = parse_all(f.view(), parser);
  ASSERT_EQ(frames.size(), 1u);
  EXPECT_EQ(frames[0].payload_len, 12);
  const auto back = decode<msg::GlobalPositionInt>(frames[0]);
  ASSERT_TRUE(back);
  EXPECT_EQ(back->time_boot_ms, 1234u);
  EXPECT_EQ(back->lat, 473977420);
  EXPECT_EQ(back->lon, 85455940);
  EXPECT_EQ(back->alt, 0);
  EXPECT_EQ(back->hdg, 0);
}

TEST(Codec, AllZeroPayloadKeepsOneByte) {
  const EncodedFrame f = encode(FrameHeader{}, msg::MissionItemReached{});
  EXPECT_EQ(f.bytes[1], 1);
  Parser parser;
  EXPECT_EQ(parse_all(f.view(), parser).size(), 1u);
}

TEST(Codec, EmptyV2PayloadFromStrippingPeersIsAccepted) {
  // some peers (node-mavlink) strip every zero: LEN = 0
  std::vector<std::uint8_t> frame = {kStxV2, 0, 0, 0, 7, 1, 1, msg::MissionItemReached::kId, 0, 0};
  std::uint16_t crc = crc_accumulate(std::span<const std::uint8_t>(frame).subspan(1), kCrcInit);
  crc = crc_accumulate(msg::MissionItemReached::kCrcExtra, crc);
  frame.push_back(static_cast<std::uint8_t>(crc));
  frame.push_back(static_cast<std::uint8_t>(crc >> 8));
  Parser parser;
  auto frames = parse_all(frame, parser);
  ASSERT_EQ(frames.size(), 1u);
  EXPECT_EQ(frames[0].payload_len, 0);
  EXPECT_EQ(decode<msg::MissionItemReached>(frames[0])->seq, 0);
}

TEST(Codec, V1SendsBaseFieldsOnlyAndRefusesWhatItCannotCarry) {
  msg::CommandAck ack;
  ack.command = 400;
  ack.target_system = 255;  // extension: not sent in v1
  FrameHeader h;
  h.version = Version::kV1;
  const EncodedFrame f = encode(h, ack);
  ASSERT_FALSE(f.empty());
  EXPECT_EQ(f.bytes[0], kStxV1);
  EXPECT_EQ(f.bytes[1], msg::CommandAck::kMinLen);

  // ids above 255 and signatures do not exist in MAVLink 1
  EXPECT_TRUE(encode(h, msg::MountOrientation{}).empty());
  h.signing = SigningParams{};
  EXPECT_TRUE(encode(h, ack).empty());
}

TEST(Codec, EncodeIntoRefusesTooSmallBuffer) {
  std::array<std::uint8_t, 10> small;
  EXPECT_EQ(encode_into(FrameHeader{}, msg::Heartbeat{}, small), 0u);
}

TEST(Codec, StringFieldsAreNulPaddedAndMayFillTheArray) {
  msg::ParamValue p;
  set_string(p.param_id, "SYSID_THISMAV");
  EXPECT_EQ(get_string(p.param_id), "SYSID_THISMAV");
  set_string(p.param_id, "EXACTLY_16_CHARS_AND_MORE");
  EXPECT_EQ(get_string(p.param_id), "EXACTLY_16_CHARS");
}

FrameHeader signed_header(const SecretKey& key, std::uint64_t ts) {
  FrameHeader h;
  h.sysid = 1;
  h.compid = 1;
  h.signing = SigningParams{key, 2, ts};
  return h;
}

TEST(Signing, SignedFrameVerifiesWithTheSameKey) {
  const SecretKey key = test::reference_key();
  msg::Heartbeat hb;
  hb.type = to_underlying(MavType::Quadrotor);
  const EncodedFrame f = encode(signed_header(key, 0x123456789aULL), hb);
  ASSERT_FALSE(f.empty());
  EXPECT_EQ(f.bytes[2], kIncompatFlagSigned);

  Parser parser(ParserConfig{key, false});
  auto frames = parse_all(f.view(), parser);
  ASSERT_EQ(frames.size(), 1u);
  ASSERT_TRUE(frames[0].signature);
  EXPECT_EQ(frames[0].signature->link_id, 2);
  EXPECT_EQ(frames[0].signature->timestamp_10us, 0x123456789aULL);
  EXPECT_EQ(parser.stats().bad_signature, 0u);
}

TEST(Signing, TamperedSignatureOrWrongKeyIsRejected) {
  const SecretKey key = test::reference_key();
  EncodedFrame f = encode(signed_header(key, 1000), msg::Heartbeat{});

  // a flipped signature byte: the CRC still passes, the signature does not
  EncodedFrame tampered = f;
  tampered.bytes[tampered.size - 1] ^= 0x01;
  Parser parser(ParserConfig{key, false});
  EXPECT_TRUE(parse_all(tampered.view(), parser).empty());
  EXPECT_EQ(parser.stats().bad_signature, 1u);
  EXPECT_EQ(parser.stats().bytes_dropped, tampered.size);

  // a tampered timestamp (replay with a new time) changes the hash too
  tampered = f;
  tampered.bytes[tampered.size - 8] ^= 0x01;
  EXPECT_TRUE(parse_all(tampered.view(), parser).empty());
  EXPECT_EQ(parser.stats().bad_signature, 2u);

  SecretKey other = key;
  other[0] ^= 0xFF;
  Parser wrong(ParserConfig{other, false});
  EXPECT_TRUE(parse_all(f.view(), wrong).empty());
  EXPECT_EQ(wrong.stats().bad_signature, 1u);

  // without a key, signatures are parsed but not checked (like the reference library without
  // signing)
  Parser open;
  EXPECT_EQ(parse_all(tampered.view(), open).size(), 1u);
}

TEST(Signing, UnsignedFramesAreRefusedOnlyWhenAsked) {
  const EncodedFrame plain = encode(FrameHeader{}, msg::Heartbeat{});
  Parser strict(ParserConfig{test::reference_key(), false});
  EXPECT_TRUE(parse_all(plain.view(), strict).empty());
  EXPECT_EQ(strict.stats().unsigned_rejected, 1u);

  Parser lenient(ParserConfig{test::reference_key(), true});
  EXPECT_EQ(parse_all(plain.view(), lenient).size(), 1u);
}

TEST(Signing, ReplayedOrStaleTimestampsAreRejected) {
  const SecretKey key = test::reference_key();
  auto signed_frame = [&](std::uint8_t link_id, std::uint64_t ts) {
    FrameHeader h = signed_header(key, ts);
    h.signing->link_id = link_id;
    return encode(h, msg::Heartbeat{});
  };
  Parser parser(ParserConfig{key, false});
  EXPECT_EQ(parse_all(signed_frame(1, 1000).view(), parser).size(), 1u);
  // the very same frame again: a replay
  EXPECT_TRUE(parse_all(signed_frame(1, 1000).view(), parser).empty());
  EXPECT_EQ(parser.stats().replayed, 1u);
  EXPECT_EQ(parse_all(signed_frame(1, 1001).view(), parser).size(), 1u);
  // another link is another stream with its own history
  EXPECT_EQ(parse_all(signed_frame(2, 500).view(), parser).size(), 1u);

  // a new stream more than one minute (6,000,000 ticks of 10 us) behind the newest timestamp is
  // refused
  const std::uint64_t now = 10'000'000;
  EXPECT_EQ(parse_all(signed_frame(3, now).view(), parser).size(), 1u);
  EXPECT_TRUE(parse_all(signed_frame(4, now - 6'000'001).view(), parser).empty());
  EXPECT_EQ(parser.stats().replayed, 2u);
  EXPECT_EQ(parse_all(signed_frame(5, now - 5'999'999).view(), parser).size(), 1u);
  EXPECT_EQ(parser.stats().bad_signature, 0u);
}

TEST(Signing, TimestampsStrictlyIncrease) {
  TimestampSource ts;
  EXPECT_EQ(ts.next(100), 100u);
  EXPECT_EQ(ts.next(100), 101u);  // same tick
  EXPECT_EQ(ts.next(50), 102u);   // clock stepped back
  EXPECT_EQ(ts.next(500), 500u);
  // 2015-01-01 + 1 s = 100000 ticks of 10 us
  EXPECT_EQ(signing_timestamp_from_unix_us((kSigningEpochUnixS + 1) * 1000000), 100000u);
}

}  // namespace
}  // namespace uavsim::common::mavlink
