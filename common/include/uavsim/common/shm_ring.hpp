// The sim API's shared-memory stream (docs/protocol.md, "Shared-memory stream"): a single-producer,
// single-consumer ring of framed records in a region both processes map, the server writing, one
// client reading. Pure: it works on memory it is given (no mapping, no files, no threads); the
// server's api/shm_transport and client_cpp's shm_stream map the region and do the wake-ups.
//
// Layout: a header (kHeaderBytes) then `capacity` bytes of data (a power of two). head and tail
// count bytes written and consumed since the start, so head - tail is what waits. A record is an
// 8-byte frame (u32 payload length, u16 type, u16 version) and its payload, padded to 8 bytes; it
// may wrap around the end of the data. Numbers are in the host's byte order: both ends run on the
// same machine by construction.
//
// Neither side trusts what the other can write. The writer keeps its own head and capacity and
// reads only the consumer's tail, which must lie between the tail it saw last and its head; the
// reader checks the header, head, every length, type and version. Anything else is kCorrupt: the
// peer is broken or hostile and the stream is over.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace uavsim::common::shm {

inline constexpr std::uint32_t kMagic = 0x52535655;  // "UVSR" in memory on a little-endian host
inline constexpr std::uint16_t kVersion = 1;
inline constexpr std::size_t kHeaderBytes = 256;
inline constexpr std::size_t kRecordHeaderBytes = 8;
inline constexpr std::size_t kMinCapacity = std::size_t{1} << 16;  // 64 KiB
inline constexpr std::size_t kMaxCapacity = std::size_t{1} << 28;  // 256 MiB

// What a record carries. The server's ring carries kStream and kTick, a client's request ring
// kStream, kRadioSend and kDone (shm_requests.hpp); each reader refuses the others.
enum class RecordType : std::uint16_t {
  kStream = 1,  // bytes of the API's message stream, as TCP would carry them (whole messages)
  kTick = 2,    // a lockstep tick with the radio frames that arrived for the client since its last
  kRadioSend = 3,  // a radio_send request, its frame's bytes raw
  kDone = 4,       // a lockstep done request
};
inline constexpr std::uint16_t kLastRecordType = 4;

// The shared header. Only the writer initialises it; afterwards the writer stores head and
// wake_pending's set, the reader stores tail and wake_pending's clear. head, tail and wake_pending
// are accessed through std::atomic_ref only (lock-free, so they work between processes).
struct RingHeader {
  std::uint32_t magic;
  std::uint16_t version;
  std::uint16_t reserved;
  std::uint64_t capacity;
  alignas(64) std::uint64_t head;
  alignas(64) std::uint64_t tail;
  // set by the writer when it wants the reader woken, cleared by the reader before it looks for
  // records: one wake-up in flight at most, however many records are written meanwhile
  alignas(64) std::uint32_t wake_pending;
};
static_assert(sizeof(RingHeader) <= kHeaderBytes);
static_assert(std::atomic_ref<std::uint64_t>::is_always_lock_free,
              "the ring's counters are shared between processes");
static_assert(std::atomic_ref<std::uint32_t>::is_always_lock_free,
              "the ring's wake flag is shared between processes");

// The names a stream's token gives (docs/protocol.md): the shared-memory object "/uavsim-TOKEN"
// (for shm_open) and its wake-up FIFO "/dev/shm/uavsim-TOKEN.wake"; with a request ring, the FIFO
// by which the client wakes the server, "/dev/shm/uavsim-TOKEN.req".
std::string object_name(const std::string& token);
std::string fifo_path(const std::string& token);
std::string request_fifo_path(const std::string& token);

// Bytes a region of this capacity takes, or 0 if the capacity is not a power of two in
// [kMinCapacity, kMaxCapacity].
std::size_t region_bytes(std::size_t capacity);

enum class RingError {
  kFull,      // the record does not fit in the free space now (the reader is behind)
  kTooLarge,  // the record could never fit
  kCorrupt,   // the peer wrote what the protocol forbids (*why says what)
};

// The producer end. Not thread-safe: one writer at a time (the owner serialises).
class RingWriter {
 public:
  // Initialises the header of `region` (region_bytes(capacity) bytes, zeroed or not) and writes
  // from its start. capacity must be valid for region_bytes (checked by the caller).
  RingWriter(void* region, std::size_t capacity);

  // Appends one record made of the concatenated parts. nullopt when written; otherwise nothing is
  // written and the error is returned (kCorrupt with *why).
  std::optional<RingError> write(RecordType type,
                                 std::span<const std::span<const std::uint8_t>> parts,
                                 std::string* why);
  // After a write: true if the reader should be woken now (it had cleared its flag). Sets the flag.
  bool take_wakeup();
  // Bytes written and not yet consumed (a reader position out of range counts as none consumed
  // since the last write; the next write reports it).
  std::size_t waiting_bytes() const;
  std::size_t capacity() const { return capacity_; }

 private:
  RingHeader* header_;
  std::uint8_t* data_;
  std::size_t capacity_;
  std::uint64_t head_ = 0;
  std::uint64_t tail_seen_ = 0;
};

// The consumer end. Not thread-safe: one reader.
class RingReader {
 public:
  // Checks the header of a mapped region of region_size bytes; nullopt with *why if it is not a
  // ring of this version that fits the region.
  static std::optional<RingReader> attach(void* region, std::size_t region_size, std::string* why);

  enum class Status { kEmpty, kRecord, kCorrupt };
  struct Record {
    RecordType type = RecordType::kStream;
    std::vector<std::uint8_t> payload;
  };
  // Takes the next record into *out and frees its space. kEmpty when none waits; kCorrupt with *why
  // when the ring breaks the protocol (the stream is then over).
  Status next(Record* out, std::string* why);
  // Before a sleep: clears the wake flag, so the writer wakes the reader for the next record. Call
  // next() again afterwards (a record may have come in between).
  void arm();

 private:
  RingReader(RingHeader* header, std::uint8_t* data, std::size_t capacity)
      : header_(header), data_(data), capacity_(capacity) {}
  RingHeader* header_;
  std::uint8_t* data_;
  std::size_t capacity_;
  std::uint64_t tail_ = 0;
};

// ---- the tick record (RecordType::kTick)

// 802.11's frames on the ns3 backend (an Ethernet MTU); 802.15.4's are at most 127
inline constexpr std::size_t kMaxRadioFrameBytes = 1500;
inline constexpr std::uint32_t kMaxRadioFramesPerTick = 1u << 20;
inline constexpr std::uint32_t kMaxVehicleIndex = 1u << 16;

// A received radio frame, as the radio_batch event's [to, from, seq, broadcast, time, sent_time,
// data] (docs/protocol.md, "Radio"), with its bytes raw.
struct RadioFrame {
  std::uint32_t to = 0;
  std::uint32_t from = 0;
  std::uint64_t seq = 0;
  bool broadcast = false;
  double time_s = 0.0;
  double sent_time_s = 0.0;
  std::vector<std::uint8_t> data;
};

struct TickRecord {
  std::int64_t tick = 0;
  double time_s = 0.0;
  std::vector<RadioFrame> frames;
};

// Appends a radio frame's encoding to *out (the frames part of a tick record). data must be
// 1..kMaxRadioFrameBytes bytes (the caller's radio guarantees it; asserted).
void encode_radio_frame(std::uint32_t to, std::uint32_t from, std::uint64_t seq, bool broadcast,
                        double time_s, double sent_time_s, std::span<const std::uint8_t> data,
                        std::vector<std::uint8_t>* out);
// The head of a tick record (tick, time, frame count), written before its frames.
std::vector<std::uint8_t> encode_tick_head(std::int64_t tick, double time_s,
                                           std::uint32_t frame_count);
// Parses a tick record's payload. nullopt with *why for anything out of range: a count or length
// past the payload's end or its limits, a time that is not finite, a vehicle index past
// kMaxVehicleIndex, bytes left over.
std::optional<TickRecord> decode_tick(std::span<const std::uint8_t> payload, std::string* why);
// The same into *out, reusing its frames' buffers (a reader of many ticks allocates once); false
// with *why, and *out unspecified, where the other gives nullopt.
bool decode_tick(std::span<const std::uint8_t> payload, TickRecord* out, std::string* why);

}  // namespace uavsim::common::shm
