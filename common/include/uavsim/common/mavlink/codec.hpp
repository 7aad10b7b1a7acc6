// Encoding MAVLink frames: header + message struct => bytes. Pure functions, no allocation.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>

#include "uavsim/common/mavlink/frame.hpp"
#include "uavsim/common/mavlink/wire.hpp"  // set_string/get_string for char-array fields
#include "uavsim/common/mavlink/generated/message_table.hpp"

namespace uavsim::common::mavlink {

// How to sign an outgoing MAVLink 2 frame.
struct SigningParams {
  SecretKey key{};
  std::uint8_t link_id = 0;
  // see TimestampSource in signing.hpp; only the low 48 bits are sent
  std::uint64_t timestamp_10us = 0;
};

// Who sends the frame and how.
struct FrameHeader {
  std::uint8_t sysid = 1;
  std::uint8_t compid = 1;
  std::uint8_t seq = 0;
  Version version = Version::kV2;
  std::optional<SigningParams> signing;  // MAVLink 2 only
};

// A frame ready to send; size 0 means it could not be encoded.
struct EncodedFrame {
  std::array<std::uint8_t, kMaxFrameLen> bytes;
  std::size_t size = 0;

  std::span<const std::uint8_t> view() const { return {bytes.data(), size}; }
  bool empty() const { return size == 0; }
};

// Frames a message whose full payload (info.max_len bytes, extensions included) is given, writing
// into out. v2 strips trailing zero bytes of the payload (keeping at least one); v1 sends the
// info.min_len base bytes. Returns the frame length, or 0 when it cannot be encoded: out too small,
// a msgid above 255 or signing requested in v1, or full_payload shorter than info.max_len.
// Thread-safe.
std::size_t encode_frame(const FrameHeader& header, const MessageInfo& info,
                         std::span<const std::uint8_t> full_payload, std::span<std::uint8_t> out);

// Frames a generated message struct (msg::Heartbeat, ...) into out; same contract as
// encode_frame().
template <class Msg>
std::size_t encode_into(const FrameHeader& header, const Msg& msg, std::span<std::uint8_t> out) {
  static constexpr MessageInfo kInfo{Msg::kId, Msg::kCrcExtra, Msg::kMinLen, Msg::kMaxLen,
                                     Msg::kName};
  std::array<std::uint8_t, Msg::kMaxLen> payload;
  msg.encode(payload.data());
  return encode_frame(header, kInfo, payload, out);
}

// Frames a generated message struct; the result is empty when it cannot be encoded (see
// encode_frame()).
template <class Msg>
EncodedFrame encode(const FrameHeader& header, const Msg& msg) {
  EncodedFrame frame;
  frame.size = encode_into(header, msg, frame.bytes);
  return frame;
}

// Decodes a frame's payload as message Msg; nullopt when the frame carries another message.
template <class Msg>
std::optional<Msg> decode(const Frame& frame) {
  if (frame.msgid != Msg::kId) return std::nullopt;
  return Msg::decode(frame.payload.data());
}

}  // namespace uavsim::common::mavlink
