#include "uavsim/common/mavlink/parser.hpp"

#include <algorithm>
#include <cstring>

#include "uavsim/common/mavlink/crc.hpp"
#include "uavsim/common/mavlink/signing.hpp"

namespace uavsim::common::mavlink {
namespace {

constexpr bool is_start_byte(std::uint8_t b) { return b == kStxV2 || b == kStxV1; }

// a new signing stream may start this far behind the newest timestamp seen: one minute in 10 us
// units (the MAVLink spec's and the reference library's limit)
constexpr std::uint64_t kNewStreamWindow10us = 60ull * 100000;

}  // namespace

Parser::Parser(const ParserConfig& config) : config_(config) {}

void Parser::reset() {
  if (emitted_len_ > 0) discard_front(emitted_len_, false);
  emitted_len_ = 0;
  discard_front(len_, true);
}

void Parser::discard_front(std::size_t n, bool count_dropped) {
  if (count_dropped) stats_.bytes_dropped += n;
  std::memmove(buf_.data(), buf_.data() + n, len_ - n);
  len_ -= n;
}

std::size_t Parser::parse(std::span<const std::uint8_t> in, const Frame** frame) {
  *frame = nullptr;
  // the frame handed out last time is no longer needed
  if (emitted_len_ > 0) {
    discard_front(emitted_len_, false);
    emitted_len_ = 0;
  }
  std::size_t used = 0;
  for (;;) {
    // buffered bytes left over from a rejected candidate: skip to their next start byte
    if (len_ > 0 && !is_start_byte(buf_[0])) {
      std::size_t i = 1;
      while (i < len_ && !is_start_byte(buf_[i])) ++i;
      discard_front(i, true);
    }
    // nothing buffered: scan the input for a start byte without copying the garbage
    if (len_ == 0) {
      std::size_t i = used;
      while (i < in.size() && !is_start_byte(in[i])) ++i;
      stats_.bytes_dropped += i - used;
      if (i == in.size()) return in.size();
      buf_[0] = in[i];
      len_ = 1;
      used = i + 1;
    }
    switch (evaluate()) {
      case Step::kNeedMore: {
        const std::size_t take = std::min(need_ - len_, in.size() - used);
        std::memcpy(buf_.data() + len_, in.data() + used, take);
        len_ += take;
        used += take;
        if (len_ < need_) return used;  // input exhausted mid-frame
        break;
      }
      case Step::kReject:
        // the start byte was false (or the frame corrupt): look again from the next byte
        discard_front(1, true);
        break;
      case Step::kSkip:
        // a genuine frame we must not deliver: drop all of it
        discard_front(need_, true);
        break;
      case Step::kEmit:
        emitted_len_ = need_;
        ++stats_.frames;
        *frame = &frame_;
        return used;
    }
  }
}

Parser::Step Parser::evaluate() {
  // header
  const bool v2 = buf_[0] == kStxV2;
  const std::size_t header_len = v2 ? kHeaderLenV2 : kHeaderLenV1;
  if (len_ < header_len) {
    need_ = header_len;
    return Step::kNeedMore;
  }
  const std::size_t payload_len = buf_[1];
  std::uint8_t incompat = 0;
  std::uint32_t msgid = 0;
  if (v2) {
    incompat = buf_[2];
    if ((incompat & ~kSupportedIncompatFlags) != 0) {
      ++stats_.bad_incompat_flags;
      return Step::kReject;
    }
    msgid = buf_[7] | (std::uint32_t{buf_[8]} << 8) | (std::uint32_t{buf_[9]} << 16);
  } else {
    msgid = buf_[5];
  }

  // the id must be known to check the CRC; its lengths bound the payload (v1 sends exactly the base
  // fields, v2 anything up to the full length, even 0 bytes from senders that strip every zero)
  const MessageInfo* info = find_message_info(msgid);
  if (info == nullptr) {
    ++stats_.unknown_msgid;
    return Step::kReject;
  }
  if (v2 ? payload_len > info->max_len : payload_len != info->min_len) {
    ++stats_.bad_length;
    return Step::kReject;
  }
  const bool is_signed = (incompat & kIncompatFlagSigned) != 0;
  const std::size_t frame_len =
      header_len + payload_len + kChecksumLen + (is_signed ? kSignatureLen : 0);
  need_ = frame_len;
  if (len_ < frame_len) return Step::kNeedMore;

  // checksum over the header after the start byte and the payload, then CRC_EXTRA
  std::uint16_t crc = crc_accumulate(
      std::span<const std::uint8_t>(buf_.data() + 1, header_len - 1 + payload_len), kCrcInit);
  crc = crc_accumulate(info->crc_extra, crc);
  const std::uint8_t* crc_bytes = buf_.data() + header_len + payload_len;
  if (crc_bytes[0] != static_cast<std::uint8_t>(crc) || crc_bytes[1] != (crc >> 8)) {
    ++stats_.bad_crc;
    return Step::kReject;
  }

  // signing policy: verify signed frames against the key; refuse unsigned ones unless allowed
  if (config_.signing_key) {
    if (is_signed) {
      const std::size_t signed_part = frame_len - std::tuple_size_v<SignatureBytes>;
      const SignatureBytes expected = compute_signature(
          *config_.signing_key, std::span<const std::uint8_t>(buf_.data(), signed_part));
      if (!std::equal(expected.begin(), expected.end(), buf_.data() + signed_part)) {
        ++stats_.bad_signature;
        return Step::kSkip;
      }
      const std::uint8_t* block = buf_.data() + header_len + payload_len + kChecksumLen;
      std::uint64_t ts = 0;
      for (int i = 0; i < 6; ++i) ts |= std::uint64_t{block[1 + i]} << (8 * i);
      if (!accept_timestamp(block[0], buf_[5], buf_[6], ts)) {
        ++stats_.replayed;
        return Step::kSkip;
      }
    } else if (!config_.accept_unsigned) {
      ++stats_.unsigned_rejected;
      return Step::kSkip;
    }
  }

  fill_frame(*info, header_len, frame_len);
  return Step::kEmit;
}

bool Parser::accept_timestamp(std::uint8_t link_id, std::uint8_t sysid, std::uint8_t compid,
                              std::uint64_t ts) {
  SigningStream* stream = nullptr;
  for (std::size_t i = 0; i < stream_count_; ++i) {
    SigningStream& s = streams_[i];
    if (s.link_id == link_id && s.sysid == sysid && s.compid == compid) stream = &s;
  }
  if (stream != nullptr) {
    // a known stream must move forward
    if (ts <= stream->timestamp_10us) return false;
  } else {
    // a new stream must not be much older than what we have seen
    if (ts + kNewStreamWindow10us < newest_timestamp_10us_) return false;
    if (stream_count_ < streams_.size()) {
      stream = &streams_[stream_count_++];
    } else {
      stream = &*std::min_element(
          streams_.begin(), streams_.end(),
          [](const auto& a, const auto& b) { return a.timestamp_10us < b.timestamp_10us; });
    }
    *stream = SigningStream{link_id, sysid, compid, 0};
  }
  stream->timestamp_10us = ts;
  newest_timestamp_10us_ = std::max(newest_timestamp_10us_, ts);
  return true;
}

void Parser::fill_frame(const MessageInfo& info, std::size_t header_len, std::size_t frame_len) {
  const bool v2 = buf_[0] == kStxV2;
  Frame& f = frame_;
  f.version = v2 ? Version::kV2 : Version::kV1;
  f.payload_len = buf_[1];
  if (v2) {
    f.incompat_flags = buf_[2];
    f.compat_flags = buf_[3];
    f.seq = buf_[4];
    f.sysid = buf_[5];
    f.compid = buf_[6];
    f.msgid = buf_[7] | (std::uint32_t{buf_[8]} << 8) | (std::uint32_t{buf_[9]} << 16);
  } else {
    f.incompat_flags = 0;
    f.compat_flags = 0;
    f.seq = buf_[2];
    f.sysid = buf_[3];
    f.compid = buf_[4];
    f.msgid = buf_[5];
  }

  // payload, zero-filled to the message's full length (a v2 sender strips trailing zeros)
  const std::size_t max_len = info.max_len;
  std::memcpy(f.payload.data(), buf_.data() + header_len, f.payload_len);
  if (max_len > f.payload_len)
    std::memset(f.payload.data() + f.payload_len, 0, max_len - f.payload_len);

  // signature block after the checksum
  if (f.incompat_flags & kIncompatFlagSigned) {
    const std::uint8_t* s = buf_.data() + header_len + f.payload_len + kChecksumLen;
    Signature sig;
    sig.link_id = s[0];
    for (int i = 0; i < 6; ++i) sig.timestamp_10us |= std::uint64_t{s[1 + i]} << (8 * i);
    std::copy_n(s + 7, sig.value.size(), sig.value.begin());
    f.signature = sig;
  } else {
    f.signature.reset();
  }
  f.info = &info;
  f.raw = std::span<const std::uint8_t>(buf_.data(), frame_len);
}

}  // namespace uavsim::common::mavlink
