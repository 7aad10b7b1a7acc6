// Streaming MAVLink 1/2 parser: feed it byte chunks of any size (a TCP stream, a file, a fuzzer),
// get back complete checksum-verified frames. Pure: no I/O, no clocks, no allocation after
// construction, never throws.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>

#include "uavsim/common/mavlink/frame.hpp"

namespace uavsim::common::mavlink {

// Why bytes were thrown away. Every byte fed is either part of an emitted frame, counted in
// bytes_dropped, or still buffered (see Parser::buffered()).
struct ParserStats {
  std::uint64_t frames = 0;         // frames emitted
  std::uint64_t bytes_dropped = 0;  // bytes that were not part of an emitted frame
  // candidate frames whose checksum failed (a truncated frame shows up here too)
  std::uint64_t bad_crc = 0;
  std::uint64_t unknown_msgid = 0;       // id not in the dialect: the CRC cannot be checked
  std::uint64_t bad_incompat_flags = 0;  // v2 incompat flags other than 0 and 0x01 (signed)
  std::uint64_t bad_length = 0;          // payload length impossible for the message id
  // signed frame whose signature does not match the configured key
  std::uint64_t bad_signature = 0;
  // unsigned frame while a key is configured and unsigned frames are refused
  std::uint64_t unsigned_rejected = 0;
  std::uint64_t replayed = 0;  // correctly signed, but its timestamp is not newer
};

struct ParserConfig {
  // when set, signed frames are verified against it, and unsigned frames are refused unless
  // accept_unsigned. Replays are refused too (MAVLink spec "Message Signing"): per stream (link id,
  // sysid, compid) timestamps must increase, and a new stream may start at most one minute before
  // the newest timestamp seen.
  std::optional<SecretKey> signing_key;
  bool accept_unsigned = false;
};

// Not thread-safe: one parser per byte stream, used from one thread.
class Parser {
 public:
  explicit Parser(const ParserConfig& config = {});

  // Consumes bytes until one frame completes or the input runs out, and returns how many bytes it
  // consumed. *frame points at the completed frame (valid until the next call) or is null when more
  // input is needed. Garbage, bad checksums, unknown ids and impossible lengths are skipped (and
  // counted) by restarting the search one byte after the rejected start byte, so a frame hidden
  // behind a false start is still found.
  std::size_t parse(std::span<const std::uint8_t> bytes, const Frame** frame);

  // Consumes all bytes, calling on_frame(const Frame&) for each complete frame in stream order.
  template <class OnFrame>
  void feed(std::span<const std::uint8_t> bytes, OnFrame&& on_frame) {
    while (!bytes.empty()) {
      const Frame* frame = nullptr;
      bytes = bytes.subspan(parse(bytes, &frame));
      if (frame != nullptr) on_frame(*frame);
    }
  }

  // Replaces the signing configuration (e.g. after SETUP_SIGNING); buffered bytes and the replay
  // history are kept.
  void configure(const ParserConfig& config) { config_ = config; }

  // Counters since construction.
  const ParserStats& stats() const { return stats_; }

  // Bytes held while waiting for the rest of a frame.
  std::size_t buffered() const { return len_ - emitted_len_; }

  // Forgets buffered bytes (e.g. on reconnect); they are counted as dropped.
  void reset();

 private:
  enum class Step { kNeedMore, kReject, kSkip, kEmit };

  // (buffered candidate starting with a start byte) => what to do with it; sets need_ for kNeedMore
  Step evaluate();
  // drops the first n buffered bytes (counting them as dropped unless they were emitted)
  void discard_front(std::size_t n, bool count_dropped);
  void fill_frame(const MessageInfo& info, std::size_t header_len, std::size_t frame_len);
  // (stream, timestamp) => false for a replay; records the timestamp otherwise
  bool accept_timestamp(std::uint8_t link_id, std::uint8_t sysid, std::uint8_t compid,
                        std::uint64_t ts);

  // replay history of signed streams: a fixed table (no allocation), the stalest stream is evicted
  // when full
  struct SigningStream {
    std::uint8_t link_id = 0;
    std::uint8_t sysid = 0;
    std::uint8_t compid = 0;
    std::uint64_t timestamp_10us = 0;
  };
  static constexpr std::size_t kMaxSigningStreams = 16;
  std::array<SigningStream, kMaxSigningStreams> streams_{};
  std::size_t stream_count_ = 0;
  std::uint64_t newest_timestamp_10us_ = 0;

  ParserConfig config_;
  ParserStats stats_;
  std::array<std::uint8_t, kMaxFrameLen> buf_{};
  std::size_t len_ = 0;   // buffered bytes
  std::size_t need_ = 0;  // bytes the current candidate needs in total
  // length of the frame handed out by the last call, still at buf_[0]
  std::size_t emitted_len_ = 0;
  Frame frame_;
};

}  // namespace uavsim::common::mavlink
