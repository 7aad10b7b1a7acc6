// libFuzzer target for the records a client writes into the shared-memory rings (docs/protocol.md,
// "Shared-memory stream"): the server decodes a client's binary radio_send and done
// (common/shm_requests.hpp), a client decodes the server's tick records (common/shm_ring.hpp). The
// first byte picks the decoder, the rest is the payload. A crash, a sanitizer finding, or a record
// that decodes but does not survive its own encoding (encode, decode again: the same fields) is a
// finding.
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "uavsim/common/shm_requests.hpp"
#include "uavsim/common/shm_ring.hpp"

namespace {

namespace shm = uavsim::common::shm;

void check(bool ok) {
  if (!ok) __builtin_trap();
}

void radio_send(std::span<const std::uint8_t> payload) {
  std::string why;
  const auto r = shm::decode_radio_send(payload, &why);
  if (!r) {
    check(!why.empty());
    return;
  }
  std::vector<std::uint8_t> again;
  shm::encode_radio_send(r->tag, r->vehicle, r->to, r->data, &again);
  // the layout has no slack: a record that decodes is its own encoding
  check(std::vector<std::uint8_t>(payload.begin(), payload.end()) == again);
}

void done(std::span<const std::uint8_t> payload) {
  std::string why;
  const auto d = shm::decode_done(payload, &why);
  if (!d) {
    check(!why.empty());
    return;
  }
  std::vector<std::uint8_t> bytes;
  shm::encode_done(*d, &bytes);
  const auto again = shm::decode_done(bytes, &why);
  check(again && again->tag == d->tag && again->quiet == d->quiet && again->tick == d->tick &&
        again->busy_until_s == d->busy_until_s && again->mavlink_seq == d->mavlink_seq);
}

void tick(std::span<const std::uint8_t> payload) {
  std::string why;
  shm::TickRecord reused;
  const auto t = shm::decode_tick(payload, &why);
  // the reusing decoder agrees with the plain one, even into a record of an earlier tick
  (void)shm::decode_tick(payload, &reused, &why);
  check(shm::decode_tick(payload, &reused, &why) == t.has_value());
  if (!t) return;
  check(reused.tick == t->tick && reused.frames.size() == t->frames.size());
  for (const shm::RadioFrame& f : t->frames) {
    check(!f.data.empty() && f.data.size() <= shm::kMaxRadioFrameBytes);
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const std::span<const std::uint8_t> payload(data + 1, size - 1);
  switch (data[0] % 3) {
    case 0:
      radio_send(payload);
      break;
    case 1:
      done(payload);
      break;
    default:
      tick(payload);
      break;
  }
  return 0;
}
