#include "uavsim/common/mavlink/codec.hpp"

#include <cstring>

#include "uavsim/common/mavlink/crc.hpp"
#include "uavsim/common/mavlink/signing.hpp"

namespace uavsim::common::mavlink {

std::size_t encode_frame(const FrameHeader& header, const MessageInfo& info,
                         std::span<const std::uint8_t> full_payload, std::span<std::uint8_t> out) {
  if (full_payload.size() < info.max_len) return 0;
  const bool v2 = header.version == Version::kV2;
  if (!v2 && (info.id > 0xFF || header.signing)) return 0;

  // payload length on the wire: v1 carries the base fields only; v2 drops trailing zeros, never
  // below one byte (the reference C library keeps one; some peers mis-handle empty payloads)
  std::size_t len = v2 ? info.max_len : info.min_len;
  if (v2) {
    while (len > 1 && full_payload[len - 1] == 0) --len;
  }
  const std::size_t header_len = v2 ? kHeaderLenV2 : kHeaderLenV1;
  const std::size_t frame_len =
      header_len + len + kChecksumLen + (header.signing ? kSignatureLen : 0);
  if (out.size() < frame_len) return 0;

  // header
  std::uint8_t* p = out.data();
  if (v2) {
    p[0] = kStxV2;
    p[1] = static_cast<std::uint8_t>(len);
    p[2] = header.signing ? kIncompatFlagSigned : 0;
    p[3] = 0;  // compat flags
    p[4] = header.seq;
    p[5] = header.sysid;
    p[6] = header.compid;
    p[7] = static_cast<std::uint8_t>(info.id);
    p[8] = static_cast<std::uint8_t>(info.id >> 8);
    p[9] = static_cast<std::uint8_t>(info.id >> 16);
  } else {
    p[0] = kStxV1;
    p[1] = static_cast<std::uint8_t>(len);
    p[2] = header.seq;
    p[3] = header.sysid;
    p[4] = header.compid;
    p[5] = static_cast<std::uint8_t>(info.id);
  }

  // payload, then the checksum over everything after the start byte plus CRC_EXTRA
  if (len > 0) std::memcpy(p + header_len, full_payload.data(), len);
  std::uint16_t crc =
      crc_accumulate(std::span<const std::uint8_t>(p + 1, header_len - 1 + len), kCrcInit);
  crc = crc_accumulate(info.crc_extra, crc);
  std::uint8_t* q = p + header_len + len;
  q[0] = static_cast<std::uint8_t>(crc);
  q[1] = static_cast<std::uint8_t>(crc >> 8);

  // signature block: link id, 48-bit timestamp, then the hash of everything before the hash itself
  if (header.signing) {
    const SigningParams& s = *header.signing;
    q[2] = s.link_id;
    for (int i = 0; i < 6; ++i) q[3 + i] = static_cast<std::uint8_t>(s.timestamp_10us >> (8 * i));
    const SignatureBytes sig = compute_signature(
        s.key, std::span<const std::uint8_t>(p, frame_len - std::tuple_size_v<SignatureBytes>));
    std::memcpy(q + 9, sig.data(), sig.size());
  }
  return frame_len;
}

}  // namespace uavsim::common::mavlink
