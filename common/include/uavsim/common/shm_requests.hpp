// A client's request ring (docs/protocol.md, "Shared-memory stream"): the records a lockstep client
// on the server's machine writes instead of request lines on TCP. Every request may go as a
// RecordType::kStream record (its JSON lines); the two a lockstep client sends every tick have a
// binary form with no JSON and no base64: radio_send (RecordType::kRadioSend) and done
// (RecordType::kDone). The server answers a binary request only when it refuses it, with the error
// reply the JSON form would get, its "id" null for tag 0 and "b<tag>" otherwise.
//
// Layouts (host byte order, as the ring's):
//   kRadioSend: u32 tag, u32 vehicle, i32 to (-1: broadcast), u16 length (1-1500), the bytes
//   kDone:      u32 tag, u8 flags (1: quiet, 2: tick present, 4: busy_until present), i64 tick,
//               f64 busy_until, u32 n, then n MAVLink sequence numbers to wait for: u32 vehicle, u8
//               seq
// Decoding checks every field's range (the server trusts nothing a client writes).
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

namespace uavsim::common::shm {

struct RadioSendRecord {
  std::uint32_t tag = 0;
  std::uint32_t vehicle = 0;
  std::int32_t to = -1;  // a vehicle index, or -1: broadcast
  std::vector<std::uint8_t> data;
};

struct DoneRecord {
  std::uint32_t tag = 0;
  bool quiet = false;
  std::optional<std::int64_t> tick;
  std::optional<double> busy_until_s;
  std::vector<std::pair<std::uint32_t, std::uint8_t>> mavlink_seq;  // (vehicle, seq)
};

// Appends the record's payload to *out. data must be 1..kMaxRadioFrameBytes bytes (asserted); to is
// a vehicle index or -1 (broadcast).
void encode_radio_send(std::uint32_t tag, std::uint32_t vehicle, std::int32_t to,
                       std::span<const std::uint8_t> data, std::vector<std::uint8_t>* out);
void encode_done(const DoneRecord& r, std::vector<std::uint8_t>* out);

// Parse a payload; nullopt with *why for anything out of range: a vehicle past kMaxVehicleIndex, a
// destination below -1, an empty or over-long frame, a busy_until that is not finite, unknown
// flags, a count past the payload, bytes left over.
std::optional<RadioSendRecord> decode_radio_send(std::span<const std::uint8_t> payload,
                                                 std::string* why);
std::optional<DoneRecord> decode_done(std::span<const std::uint8_t> payload, std::string* why);

}  // namespace uavsim::common::shm
