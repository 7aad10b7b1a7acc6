#include "uavsim/common/shm_requests.hpp"

#include <cassert>
#include <cmath>

#include "shm_codec.hpp"
#include "uavsim/common/shm_ring.hpp"

namespace uavsim::common::shm {

namespace {

using codec::append;
using codec::Cursor;

constexpr std::uint8_t kQuiet = 1;
constexpr std::uint8_t kHasTick = 2;
constexpr std::uint8_t kHasBusyUntil = 4;
constexpr std::size_t kSeqBytes = 4 + 1;  // vehicle, seq

}  // namespace

void encode_radio_send(std::uint32_t tag, std::uint32_t vehicle, std::int32_t to,
                       std::span<const std::uint8_t> data, std::vector<std::uint8_t>* out) {
  assert(!data.empty() && data.size() <= kMaxRadioFrameBytes);
  append(out, tag);
  append(out, vehicle);
  append(out, to);
  append(out, static_cast<std::uint16_t>(data.size()));
  out->insert(out->end(), data.begin(), data.end());
}

std::optional<RadioSendRecord> decode_radio_send(std::span<const std::uint8_t> payload,
                                                 std::string* why) {
  Cursor c(payload);
  RadioSendRecord r;
  std::uint16_t length = 0;
  if (!c.take(&r.tag) || !c.take(&r.vehicle) || !c.take(&r.to) || !c.take(&length)) {
    *why = "a radio_send record shorter than its head";
    return std::nullopt;
  }
  if (r.vehicle >= kMaxVehicleIndex || r.to < -1 ||
      r.to >= static_cast<std::int32_t>(kMaxVehicleIndex) || length == 0 ||
      length > kMaxRadioFrameBytes) {
    *why = "a radio_send record with a field out of range";
    return std::nullopt;
  }
  if (!c.take_bytes(length, &r.data) || c.left() != 0) {
    *why =
        "a radio_send record whose frame is not its announced " + std::to_string(length) + " bytes";
    return std::nullopt;
  }
  return r;
}

void encode_done(const DoneRecord& r, std::vector<std::uint8_t>* out) {
  const std::uint8_t flags =
      (r.quiet ? kQuiet : 0) | (r.tick ? kHasTick : 0) | (r.busy_until_s ? kHasBusyUntil : 0);
  append(out, r.tag);
  append(out, flags);
  append(out, r.tick.value_or(0));
  append(out, r.busy_until_s.value_or(0.0));
  append(out, static_cast<std::uint32_t>(r.mavlink_seq.size()));
  for (const auto& [vehicle, seq] : r.mavlink_seq) {
    append(out, vehicle);
    append(out, seq);
  }
}

std::optional<DoneRecord> decode_done(std::span<const std::uint8_t> payload, std::string* why) {
  Cursor c(payload);
  DoneRecord r;
  std::uint8_t flags = 0;
  std::int64_t tick = 0;
  double busy = 0.0;
  std::uint32_t count = 0;
  if (!c.take(&r.tag) || !c.take(&flags) || !c.take(&tick) || !c.take(&busy) || !c.take(&count)) {
    *why = "a done record shorter than its head";
    return std::nullopt;
  }
  if ((flags & ~(kQuiet | kHasTick | kHasBusyUntil)) != 0 ||
      ((flags & kHasBusyUntil) && !std::isfinite(busy))) {
    *why = "a done record with unknown flags or a busy_until that is not a time";
    return std::nullopt;
  }
  // each entry takes its fixed bytes: a count past what is left is a lie
  if (count > kMaxVehicleIndex || count > c.left() / kSeqBytes) {
    *why = "a done record announcing " + std::to_string(count) + " sequence numbers in " +
           std::to_string(c.left()) + " bytes";
    return std::nullopt;
  }
  r.quiet = (flags & kQuiet) != 0;
  if (flags & kHasTick) r.tick = tick;
  if (flags & kHasBusyUntil) r.busy_until_s = busy;
  r.mavlink_seq.resize(count);
  for (auto& [vehicle, seq] : r.mavlink_seq) {
    if (!c.take(&vehicle) || !c.take(&seq) || vehicle >= kMaxVehicleIndex) {
      *why = "a done record's sequence number of a vehicle out of range";
      return std::nullopt;
    }
  }
  if (c.left() != 0) {
    *why = std::to_string(c.left()) + " bytes after a done record's last sequence number";
    return std::nullopt;
  }
  return r;
}

}  // namespace uavsim::common::shm
