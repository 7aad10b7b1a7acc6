#include "uavsim/common/shm_ring.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstring>
#include <new>

#include "shm_codec.hpp"

namespace uavsim::common::shm {

namespace {

using std::uint16_t;
using std::uint32_t;
using std::uint64_t;
using std::uint8_t;

std::atomic_ref<uint64_t> head_of(RingHeader* h) { return std::atomic_ref<uint64_t>(h->head); }
std::atomic_ref<uint64_t> tail_of(RingHeader* h) { return std::atomic_ref<uint64_t>(h->tail); }
std::atomic_ref<uint32_t> wake_of(RingHeader* h) {
  return std::atomic_ref<uint32_t>(h->wake_pending);
}

using codec::append;
using codec::Cursor;

constexpr std::size_t padded(std::size_t n) { return (n + 7) & ~std::size_t{7}; }

bool power_of_two(std::size_t n) { return n != 0 && (n & (n - 1)) == 0; }

// copies into / out of the ring at a byte position, wrapping at the end
// (n == 0 returns first: an empty part, e.g. a tick without radio frames, may come as a null span, and
// memcpy's pointers must not be null even for no bytes)
void put(uint8_t* data, std::size_t capacity, uint64_t pos, const uint8_t* src, std::size_t n) {
  if (n == 0) return;
  const std::size_t at = static_cast<std::size_t>(pos & (capacity - 1));
  const std::size_t first = std::min(n, capacity - at);
  std::memcpy(data + at, src, first);
  std::memcpy(data, src + first, n - first);
}

void get(const uint8_t* data, std::size_t capacity, uint64_t pos, uint8_t* dst, std::size_t n) {
  if (n == 0) return;
  const std::size_t at = static_cast<std::size_t>(pos & (capacity - 1));
  const std::size_t first = std::min(n, capacity - at);
  std::memcpy(dst, data + at, first);
  std::memcpy(dst + first, data, n - first);
}

// a frame's fixed part: to, from, seq, broadcast, time, sent_time, length
constexpr std::size_t kFrameFixedBytes = 4 + 4 + 8 + 1 + 8 + 8 + 2;

}  // namespace

// (appended, not "literal" + token: GCC 12 warns a false -Wrestrict on that)
std::string object_name(const std::string& token) {
  std::string name = "/uavsim-";
  name += token;
  return name;
}

std::string fifo_path(const std::string& token) {
  std::string path = "/dev/shm/uavsim-";
  path += token;
  path += ".wake";
  return path;
}

std::string request_fifo_path(const std::string& token) {
  std::string path = "/dev/shm/uavsim-";
  path += token;
  path += ".req";
  return path;
}

std::size_t region_bytes(std::size_t capacity) {
  if (!power_of_two(capacity) || capacity < kMinCapacity || capacity > kMaxCapacity) return 0;
  return kHeaderBytes + capacity;
}

// ---------------------------------------------------------------------------------------------------
// writer

RingWriter::RingWriter(void* region, std::size_t capacity)
    : header_(static_cast<RingHeader*>(region)),
      data_(static_cast<uint8_t*>(region) + kHeaderBytes),
      capacity_(capacity) {
  assert(region_bytes(capacity) != 0);
  std::memset(region, 0, kHeaderBytes);
  header_->magic = kMagic;
  header_->version = kVersion;
  header_->capacity = capacity;
  // the header's plain fields are published with the counters' first release
  tail_of(header_).store(0, std::memory_order_release);
  head_of(header_).store(0, std::memory_order_release);
}

std::optional<RingError> RingWriter::write(RecordType type,
                                           std::span<const std::span<const uint8_t>> parts,
                                           std::string* why) {
  std::size_t payload = 0;
  for (const auto& p : parts) payload += p.size();
  const std::size_t need = kRecordHeaderBytes + padded(payload);
  if (payload > UINT32_MAX || need > capacity_) return RingError::kTooLarge;
  // the reader's tail: between what it had consumed before and what was written
  const uint64_t tail = tail_of(header_).load(std::memory_order_acquire);
  if (tail < tail_seen_ || tail > head_) {
    *why = "the reader's position " + std::to_string(tail) + " is outside [" +
           std::to_string(tail_seen_) + ", " + std::to_string(head_) + "]";
    return RingError::kCorrupt;
  }
  tail_seen_ = tail;
  if (capacity_ - static_cast<std::size_t>(head_ - tail) < need) return RingError::kFull;
  // frame, payload parts, padding; published by the head's release store
  const uint32_t length = static_cast<uint32_t>(payload);
  const uint16_t type_value = static_cast<uint16_t>(type);
  uint8_t frame[kRecordHeaderBytes];
  std::memcpy(frame, &length, 4);
  std::memcpy(frame + 4, &type_value, 2);
  std::memcpy(frame + 6, &kVersion, 2);
  uint64_t pos = head_;
  put(data_, capacity_, pos, frame, sizeof(frame));
  pos += sizeof(frame);
  for (const auto& p : parts) {
    put(data_, capacity_, pos, p.data(), p.size());
    pos += p.size();
  }
  head_ += need;
  head_of(header_).store(head_, std::memory_order_release);
  return std::nullopt;
}

std::size_t RingWriter::waiting_bytes() const {
  const uint64_t tail = tail_of(header_).load(std::memory_order_acquire);
  const uint64_t consumed = tail >= tail_seen_ && tail <= head_ ? tail : tail_seen_;
  return static_cast<std::size_t>(head_ - consumed);
}

bool RingWriter::take_wakeup() {
  // seq_cst against the reader's arm(): either it sees the new head, or this sees its cleared flag
  return wake_of(header_).exchange(1, std::memory_order_seq_cst) == 0;
}

// ---------------------------------------------------------------------------------------------------
// reader

std::optional<RingReader> RingReader::attach(void* region, std::size_t region_size,
                                             std::string* why) {
  if (region == nullptr || region_size < kHeaderBytes) {
    *why = "the region is smaller than the ring's header";
    return std::nullopt;
  }
  auto* header = static_cast<RingHeader*>(region);
  if (header->magic != kMagic) {
    *why = "not a uavsim ring (bad magic)";
    return std::nullopt;
  }
  if (header->version != kVersion) {
    *why = "ring version " + std::to_string(header->version) + ", this client reads " +
           std::to_string(kVersion);
    return std::nullopt;
  }
  const uint64_t capacity = header->capacity;
  if (region_bytes(static_cast<std::size_t>(capacity)) == 0 ||
      region_bytes(static_cast<std::size_t>(capacity)) > region_size) {
    *why = "the ring's capacity " + std::to_string(capacity) + " does not fit its region of " +
           std::to_string(region_size) + " bytes";
    return std::nullopt;
  }
  RingReader reader(header, static_cast<uint8_t*>(region) + kHeaderBytes,
                    static_cast<std::size_t>(capacity));
  reader.tail_ = tail_of(header).load(std::memory_order_acquire);
  return reader;
}

RingReader::Status RingReader::next(Record* out, std::string* why) {
  const uint64_t head = head_of(header_).load(std::memory_order_acquire);
  if (head == tail_) return Status::kEmpty;
  const uint64_t waiting = head - tail_;
  if (head < tail_ || waiting > capacity_ || waiting < kRecordHeaderBytes || waiting % 8 != 0) {
    *why = "the writer's position " + std::to_string(head) + " is inconsistent with the reader's " +
           std::to_string(tail_);
    return Status::kCorrupt;
  }
  uint8_t frame[kRecordHeaderBytes];
  get(data_, capacity_, tail_, frame, sizeof(frame));
  uint32_t length = 0;
  uint16_t type = 0, version = 0;
  std::memcpy(&length, frame, 4);
  std::memcpy(&type, frame + 4, 2);
  std::memcpy(&version, frame + 6, 2);
  if (version != kVersion) {
    *why = "a record of version " + std::to_string(version);
    return Status::kCorrupt;
  }
  if (type == 0 || type > kLastRecordType) {
    *why = "a record of unknown type " + std::to_string(type);
    return Status::kCorrupt;
  }
  const std::size_t need = kRecordHeaderBytes + padded(length);
  if (need > waiting) {
    *why = "a record of " + std::to_string(length) + " bytes where " + std::to_string(waiting) +
           " were written";
    return Status::kCorrupt;
  }
  out->type = static_cast<RecordType>(type);
  out->payload.resize(length);
  get(data_, capacity_, tail_ + kRecordHeaderBytes, out->payload.data(), length);
  tail_ += need;
  tail_of(header_).store(tail_, std::memory_order_release);
  return Status::kRecord;
}

void RingReader::arm() { wake_of(header_).store(0, std::memory_order_seq_cst); }

// ---------------------------------------------------------------------------------------------------
// tick records

void encode_radio_frame(uint32_t to, uint32_t from, uint64_t seq, bool broadcast, double time_s,
                        double sent_time_s, std::span<const uint8_t> data,
                        std::vector<uint8_t>* out) {
  assert(!data.empty() && data.size() <= kMaxRadioFrameBytes);
  append(out, to);
  append(out, from);
  append(out, seq);
  append(out, static_cast<uint8_t>(broadcast ? 1 : 0));
  append(out, time_s);
  append(out, sent_time_s);
  append(out, static_cast<uint16_t>(data.size()));
  out->insert(out->end(), data.begin(), data.end());
}

std::vector<uint8_t> encode_tick_head(std::int64_t tick, double time_s, uint32_t frame_count) {
  std::vector<uint8_t> out;
  append(&out, tick);
  append(&out, time_s);
  append(&out, frame_count);
  return out;
}

bool decode_tick(std::span<const uint8_t> payload, TickRecord* out, std::string* why) {
  Cursor c(payload);
  TickRecord& r = *out;
  uint32_t count = 0;
  if (!c.take(&r.tick) || !c.take(&r.time_s) || !c.take(&count)) {
    *why = "a tick record shorter than its head";
    return false;
  }
  if (r.tick < 0 || !std::isfinite(r.time_s) || r.time_s < 0.0) {
    *why = "a tick record with tick " + std::to_string(r.tick) + " at an impossible time";
    return false;
  }
  // each frame takes at least its fixed part and one byte: a count past that is a lie
  if (count > kMaxRadioFramesPerTick || count > c.left() / (kFrameFixedBytes + 1)) {
    *why = "a tick record announcing " + std::to_string(count) + " radio frames in " +
           std::to_string(c.left()) + " bytes";
    return false;
  }
  r.frames.resize(count);
  for (RadioFrame& f : r.frames) {
    uint8_t broadcast = 0;
    uint16_t length = 0;
    if (!c.take(&f.to) || !c.take(&f.from) || !c.take(&f.seq) || !c.take(&broadcast) ||
        !c.take(&f.time_s) || !c.take(&f.sent_time_s) || !c.take(&length)) {
      *why = "a radio frame cut short";
      return false;
    }
    if (f.to >= kMaxVehicleIndex || f.from >= kMaxVehicleIndex || broadcast > 1 ||
        !std::isfinite(f.time_s) || !std::isfinite(f.sent_time_s) || length == 0 ||
        length > kMaxRadioFrameBytes) {
      *why = "a radio frame with a field out of range";
      return false;
    }
    f.broadcast = broadcast == 1;
    if (!c.take_bytes(length, &f.data)) {
      *why = "a radio frame's bytes cut short";
      return false;
    }
  }
  if (c.left() != 0) {
    *why = std::to_string(c.left()) + " bytes after a tick record's last frame";
    return false;
  }
  return true;
}

std::optional<TickRecord> decode_tick(std::span<const uint8_t> payload, std::string* why) {
  TickRecord r;
  if (!decode_tick(payload, &r, why)) return std::nullopt;
  return r;
}

}  // namespace uavsim::common::shm
