// libFuzzer target for the MAVLink parser. Beyond "no crash, no sanitizer report" it checks
// invariants:
//   * every input byte ends up in a frame, in bytes_dropped, or buffered;
//   * an emitted frame, parsed again on its own, is emitted again unchanged;
//   * a frame with a generated struct re-encodes (unsigned) to a frame that decodes to the same
//   payload.
// Built by run_parser_fuzz.sh with clang++ -fsanitize=fuzzer,address,undefined.
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <tuple>

#include "uavsim/common/mavlink/codec.hpp"
#include "uavsim/common/mavlink/parser.hpp"
#include "uavsim/common/mavlink/generated/messages.hpp"

namespace mav = uavsim::common::mavlink;

namespace {

void check(bool ok) {
  if (!ok) __builtin_trap();
}

// (frame) => its payload re-encoded through the generated struct, or nothing when no struct exists
void check_reencode(const mav::Frame& frame) {
  mav::FrameHeader h;
  h.sysid = frame.sysid;
  h.compid = frame.compid;
  h.seq = frame.seq;
  h.version = frame.version;
  std::apply(
      [&](auto... tag) {
        (
            [&] {
              using M = decltype(tag);
              if (frame.msgid != M::kId) return;
              const mav::EncodedFrame again = mav::encode(h, M::decode(frame.payload.data()));
              check(!again.empty());
              mav::Parser p;
              int n = 0;
              p.feed(again.view(), [&](const mav::Frame& g) {
                // v1 carries only the base fields
                const std::size_t len =
                    frame.version == mav::Version::kV1 ? M::kMinLen : M::kMaxLen;
                check(std::memcmp(g.payload.data(), frame.payload.data(), len) == 0);
                ++n;
              });
              check(n == 1);
            }(),
            ...);
      },
      mav::msg::AllMessages{});
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 2) return 0;
  // first byte: signing policy and chunking of the rest
  const std::uint8_t mode = data[0];
  mav::ParserConfig config;
  if (mode & 0x01) {
    mav::SecretKey key{};
    for (std::size_t i = 0; i < key.size(); ++i) key[i] = static_cast<std::uint8_t>(i);
    config.signing_key = key;
    config.accept_unsigned = (mode & 0x02) != 0;
  }
  const std::size_t chunk = 1 + (mode >> 2);
  ++data;
  --size;

  mav::Parser parser(config);
  std::size_t frame_bytes = 0;
  for (std::size_t i = 0; i < size; i += chunk) {
    const std::size_t n = std::min(chunk, size - i);
    parser.feed(std::span<const std::uint8_t>(data + i, n), [&](const mav::Frame& f) {
      check(f.info != nullptr && f.info->id == f.msgid);
      check(f.raw.size() <= mav::kMaxFrameLen);
      frame_bytes += f.raw.size();

      mav::Parser alone(config);
      int n_alone = 0;
      alone.feed(f.raw, [&](const mav::Frame& g) {
        check(g.raw.size() == f.raw.size() &&
              std::memcmp(g.raw.data(), f.raw.data(), g.raw.size()) == 0);
        ++n_alone;
      });
      check(n_alone == 1);
      check_reencode(f);
    });
  }
  check(frame_bytes + parser.stats().bytes_dropped + parser.buffered() == size);
  return 0;
}
