#include <algorithm>
#include <cmath>
#include <map>
#include <set>

#include "uavsim/client/gcs_link.hpp"

namespace uavsim::client {

namespace {

constexpr uint8_t kMagic0 = 'U';
constexpr uint8_t kMagic1 = 'G';
constexpr uint8_t kVersion = 1;
constexpr size_t kHeaderBytes =
    2 + 1 + 1 + 8 + 4 + 2 + 2;  // magic, version, sender, time, low water, counts
constexpr size_t kAckBytes = 4;
constexpr size_t kMessageHeaderBytes = 4 + 2 + 2;  // id, topic, length

void put16(std::vector<uint8_t>& b, uint16_t v) {
  b.push_back(static_cast<uint8_t>(v >> 8));
  b.push_back(static_cast<uint8_t>(v));
}
void put32(std::vector<uint8_t>& b, uint32_t v) {
  for (int s = 24; s >= 0; s -= 8) b.push_back(static_cast<uint8_t>(v >> s));
}
void put64(std::vector<uint8_t>& b, uint64_t v) {
  for (int s = 56; s >= 0; s -= 8) b.push_back(static_cast<uint8_t>(v >> s));
}
void set16(std::vector<uint8_t>& b, size_t at, uint16_t v) {
  b[at] = static_cast<uint8_t>(v >> 8);
  b[at + 1] = static_cast<uint8_t>(v);
}

// bounds-checked big-endian reader
struct Reader {
  const uint8_t* p;
  size_t n;
  size_t at = 0;
  bool ok = true;
  uint64_t get(size_t bytes) {
    if (!ok || n - at < bytes) {
      ok = false;
      return 0;
    }
    uint64_t v = 0;
    for (size_t k = 0; k < bytes; ++k) v = (v << 8) | p[at + k];
    at += bytes;
    return v;
  }
};

}  // namespace

const char* gcs_link_status_name(GcsLinkStatus s) {
  switch (s) {
    case GcsLinkStatus::kOk:
      return "ok";
    case GcsLinkStatus::kPayloadTooLarge:
      return "payload_too_large";
    case GcsLinkStatus::kQueueFull:
      return "queue_full";
    case GcsLinkStatus::kMalformed:
      return "malformed";
    case GcsLinkStatus::kIo:
      return "io";
  }
  return "unknown";
}

struct GcsLinkCore::Impl {
  struct Outgoing {
    uint16_t topic = 0;
    std::vector<uint8_t> payload;
    bool sent = false;
  };

  GcsLinkConfig config;
  int64_t period_us = 100000;
  std::optional<int64_t> next_poll_us;
  uint32_t next_id = 0;
  std::map<uint32_t, Outgoing> outgoing;  // by id: unacknowledged, oldest first
  std::vector<uint32_t> acks;             // ids received, to acknowledge in the next packet
  // receiving side: ids delivered at or above the peer's low-water mark (below it: never sent
  // again)
  std::optional<uint32_t> peer_low_water;
  std::set<uint32_t> delivered_ids;
  std::vector<GcsMessage> inbox;
  std::optional<int64_t> clock_offset_us;
  GcsLinkStats stats;

  uint32_t low_water() const { return outgoing.empty() ? next_id : outgoing.begin()->first; }
};

GcsLinkCore::GcsLinkCore(const GcsLinkConfig& config) : impl_(std::make_unique<Impl>()) {
  impl_->config = config;
  impl_->period_us = std::max<int64_t>(1, std::llround(config.period_s * 1e6));
}
GcsLinkCore::~GcsLinkCore() = default;
GcsLinkCore::GcsLinkCore(GcsLinkCore&&) noexcept = default;
GcsLinkCore& GcsLinkCore::operator=(GcsLinkCore&&) noexcept = default;

GcsLinkStatus GcsLinkCore::publish(uint16_t topic, const std::vector<uint8_t>& payload) {
  Impl& s = *impl_;
  if (payload.size() > s.config.max_payload_bytes || payload.size() > 0xFFFF ||
      kHeaderBytes + kMessageHeaderBytes + payload.size() > s.config.max_packet_bytes) {
    return GcsLinkStatus::kPayloadTooLarge;
  }
  // latest only: the new message replaces the one still pending on its topic
  if (topic & kLatestOnlyTopicBit) {
    for (auto it = s.outgoing.begin(); it != s.outgoing.end();) {
      if (it->second.topic == topic) {
        it = s.outgoing.erase(it);
        ++s.stats.messages_superseded;
      } else {
        ++it;
      }
    }
  }
  if (s.outgoing.size() >= s.config.max_queued_messages) return GcsLinkStatus::kQueueFull;
  s.outgoing.emplace(s.next_id++, Impl::Outgoing{topic, payload, false});
  ++s.stats.messages_published;
  return GcsLinkStatus::kOk;
}

GcsLinkStatus GcsLinkCore::on_packet(const uint8_t* data, size_t size, int64_t now_us) {
  Impl& s = *impl_;
  // parse everything before applying anything: a malformed packet changes nothing
  Reader r{data, size};
  const auto m0 = r.get(1), m1 = r.get(1), version = r.get(1);
  const auto sender = static_cast<uint8_t>(r.get(1));
  const auto gcs_time_us = static_cast<int64_t>(r.get(8));
  const auto low_water = static_cast<uint32_t>(r.get(4));
  const auto n_acks = r.get(2), n_msgs = r.get(2);
  if (!r.ok || m0 != kMagic0 || m1 != kMagic1 || version != kVersion) {
    ++s.stats.packets_malformed;
    return GcsLinkStatus::kMalformed;
  }
  std::vector<uint32_t> acked;
  for (uint64_t k = 0; k < n_acks && r.ok; ++k) acked.push_back(static_cast<uint32_t>(r.get(4)));
  std::vector<GcsMessage> msgs;
  for (uint64_t k = 0; k < n_msgs && r.ok; ++k) {
    GcsMessage m;
    m.from = sender;
    m.id = static_cast<uint32_t>(r.get(4));
    m.topic = static_cast<uint16_t>(r.get(2));
    const auto len = static_cast<size_t>(r.get(2));
    if (!r.ok || r.n - r.at < len) {
      r.ok = false;
      break;
    }
    m.payload.assign(data + r.at, data + r.at + len);
    r.at += len;
    msgs.push_back(std::move(m));
  }
  if (!r.ok || r.at != size) {
    ++s.stats.packets_malformed;
    return GcsLinkStatus::kMalformed;
  }
  ++s.stats.packets_received;

  // acknowledged messages leave the queue
  for (uint32_t id : acked) s.stats.messages_acked += s.outgoing.erase(id);

  // the peer will never send ids below its low-water mark again: forget them (ids of this link grow
  // monotonically; an old, reordered packet cannot lower the mark)
  if (!s.peer_low_water || low_water > *s.peer_low_water) {
    s.peer_low_water = low_water;
    s.delivered_ids.erase(s.delivered_ids.begin(), s.delivered_ids.lower_bound(low_water));
  }
  for (GcsMessage& m : msgs) {
    s.acks.push_back(m.id);  // acknowledge every copy: the previous ack may have been lost
    if (m.id < *s.peer_low_water || !s.delivered_ids.insert(m.id).second) {
      ++s.stats.duplicates;
      continue;
    }
    ++s.stats.messages_received;
    s.inbox.push_back(std::move(m));
  }

  // Algorithm 6 (seed 6.3): on a UAV, keep the least local - GCS time difference
  if (sender == kGcsId && s.config.local_id != kGcsId) {
    const int64_t difference = now_us - gcs_time_us;
    if (!s.clock_offset_us || *s.clock_offset_us > difference) s.clock_offset_us = difference;
  }
  return GcsLinkStatus::kOk;
}

std::optional<std::vector<uint8_t>> GcsLinkCore::poll(int64_t now_us) {
  Impl& s = *impl_;
  if (s.next_poll_us && now_us < *s.next_poll_us) return std::nullopt;
  // the next period: on the fixed grid, or from now if more than a period late
  s.next_poll_us = s.next_poll_us ? *s.next_poll_us + s.period_us : now_us + s.period_us;
  if (*s.next_poll_us <= now_us) s.next_poll_us = now_us + s.period_us;

  std::vector<uint8_t> b;
  b.reserve(s.config.max_packet_bytes);
  b.push_back(kMagic0);
  b.push_back(kMagic1);
  b.push_back(kVersion);
  b.push_back(s.config.local_id);
  // the GCS's current time, or zero from a UAV (seed 6.3, note 32)
  put64(b, s.config.local_id == kGcsId ? static_cast<uint64_t>(now_us) : 0u);
  put32(b, s.low_water());
  const size_t counts_at = b.size();
  put16(b, 0);
  put16(b, 0);

  // acknowledgements first (they free the peer's queue), then messages oldest first, as many as fit
  size_t n_acks = 0;
  while (n_acks < s.acks.size() && n_acks < 0xFFFF &&
         b.size() + kAckBytes <= s.config.max_packet_bytes) {
    put32(b, s.acks[n_acks++]);
  }
  s.acks.erase(s.acks.begin(), s.acks.begin() + static_cast<std::ptrdiff_t>(n_acks));
  size_t n_msgs = 0;
  for (auto& [id, m] : s.outgoing) {
    if (n_msgs == 0xFFFF ||
        b.size() + kMessageHeaderBytes + m.payload.size() > s.config.max_packet_bytes)
      break;
    put32(b, id);
    put16(b, m.topic);
    put16(b, static_cast<uint16_t>(m.payload.size()));
    b.insert(b.end(), m.payload.begin(), m.payload.end());
    if (m.sent) ++s.stats.retransmissions;
    m.sent = true;
    ++n_msgs;
  }
  set16(b, counts_at, static_cast<uint16_t>(n_acks));
  set16(b, counts_at + 2, static_cast<uint16_t>(n_msgs));
  ++s.stats.packets_sent;
  return b;
}

int64_t GcsLinkCore::next_poll_us() const { return impl_->next_poll_us.value_or(INT64_MIN); }

std::vector<GcsMessage> GcsLinkCore::take_received() {
  std::vector<GcsMessage> out;
  out.swap(impl_->inbox);
  return out;
}

std::optional<int64_t> GcsLinkCore::clock_offset_us() const { return impl_->clock_offset_us; }

std::optional<int64_t> GcsLinkCore::to_gcs_time_us(int64_t local_us) const {
  if (!impl_->clock_offset_us) return std::nullopt;
  return local_us - *impl_->clock_offset_us;
}

std::optional<int64_t> GcsLinkCore::to_local_time_us(int64_t gcs_us) const {
  if (!impl_->clock_offset_us) return std::nullopt;
  return gcs_us + *impl_->clock_offset_us;
}

size_t GcsLinkCore::pending() const { return impl_->outgoing.size(); }

size_t GcsLinkCore::pending(uint16_t topic) const {
  return static_cast<size_t>(std::count_if(impl_->outgoing.begin(), impl_->outgoing.end(),
                                           [&](const auto& e) { return e.second.topic == topic; }));
}

const GcsLinkStats& GcsLinkCore::stats() const { return impl_->stats; }
const GcsLinkConfig& GcsLinkCore::config() const { return impl_->config; }

}  // namespace uavsim::client
