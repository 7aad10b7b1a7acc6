#include "radio_messages.hpp"

#include <algorithm>
#include <cmath>

namespace uavsim::missions::coverage {

namespace {

constexpr size_t kBeaconHeaderBytes = 14;
constexpr size_t kRecordBytes = 14;
constexpr size_t kAggregateHeaderBytes = 29;
constexpr size_t kRunHeaderBytes = 2;  // a run's repeat and interval count
constexpr size_t kIntervalBytes = 4;
static_assert(kMinFrameBytes == kAggregateHeaderBytes + kRunHeaderBytes + kIntervalBytes);
static_assert(kMinFrameBytes >= kBeaconHeaderBytes + kRecordBytes);
static_assert(kBeaconHeaderBytes + kMaxRecordsPerBeacon * kRecordBytes <= kMaxFrameBytes);
constexpr int kMaxFragments = 255;
constexpr unsigned kFlagGoingHome = 1;
constexpr unsigned kFlagLanded = 2;
constexpr unsigned kRoundShift = 2;  // bits 2-4: the survey round (mod kRounds)
constexpr unsigned kFlagHomebound = 32;
// a record's hop count byte: bits 0-6 the hops (a flock of at most kMaxAgents is fewer hops deep),
// bit 7 the agent's landed flag as last heard
constexpr unsigned kHopsMask = 0x7F;
constexpr unsigned kRecordLanded = 0x80;

// little-endian writer and bounds-checked reader
struct Writer {
  Frame& f;
  void u8(unsigned v) { f.push_back(static_cast<uint8_t>(v)); }
  void u16(unsigned v) {
    u8(v & 0xFF);
    u8((v >> 8) & 0xFF);
  }
  void i16(int v) { u16(static_cast<uint16_t>(static_cast<int16_t>(v))); }
  void u64(uint64_t v) {
    for (int i = 0; i < 8; ++i) u8(static_cast<unsigned>((v >> (8 * i)) & 0xFF));
  }
};

struct Reader {
  const Frame& f;
  size_t pos = 0;
  bool ok = true;
  unsigned u8() {
    if (pos >= f.size()) {
      ok = false;
      return 0;
    }
    return f[pos++];
  }
  unsigned u16() {
    const unsigned lo = u8();
    return lo | (u8() << 8);
  }
  int i16() { return static_cast<int16_t>(static_cast<uint16_t>(u16())); }
  int i8() { return static_cast<int8_t>(static_cast<uint8_t>(u8())); }
  uint64_t u64() {
    uint64_t v = 0;
    for (int i = 0; i < 8; ++i) v |= static_cast<uint64_t>(u8()) << (8 * i);
    return v;
  }
};

int to_dm(double v_m) {
  if (!std::isfinite(v_m)) return 0;
  return static_cast<int>(std::clamp(std::lround(v_m * 10.0), -32767L, 32767L));
}
unsigned heading_code(double rad) {
  if (!std::isfinite(rad)) return 0;
  const double turns = rad / (2.0 * kPi);
  const double frac = turns - std::floor(turns);  // [0, 1)
  return static_cast<unsigned>(std::lround(frac * 65536.0)) & 0xFFFF;
}
double heading_rad(unsigned code) {
  const double r = code * (2.0 * kPi / 65536.0);
  return r > kPi ? r - 2.0 * kPi : r;
}
unsigned speed_code(double v_m_s) {
  if (!std::isfinite(v_m_s)) return 0;
  return static_cast<uint8_t>(
      static_cast<int8_t>(std::clamp(std::lround(v_m_s * 10.0), -127L, 127L)));
}

void write_state(Writer& w, const AgentRecord& r, const RadioFrameOrigin& o) {
  w.u16(r.seq);
  w.i16(to_dm(r.x_m - o.x_m));
  w.i16(to_dm(r.y_m - o.y_m));
  w.u16(heading_code(r.heading_rad));
  w.u8(speed_code(r.vx_m_s));
  w.u8(speed_code(r.vy_m_s));
}

void read_state(Reader& r, AgentRecord& a, const RadioFrameOrigin& o) {
  a.seq = static_cast<uint16_t>(r.u16());
  a.x_m = o.x_m + r.i16() / 10.0;
  a.y_m = o.y_m + r.i16() / 10.0;
  a.heading_rad = heading_rad(r.u16());
  a.vx_m_s = r.i8() / 10.0;
  a.vy_m_s = r.i8() / 10.0;
}

// An APD as runs of stripes with identical interval lists, ends in 0.1 m rounded inwards (a run
// never claims more than was covered); at most max_intervals intervals a stripe (the rest dropped:
// less is claimed, never more). Every run's ends in one flat list: an encoder allocates a few
// times a message, not once a stripe.
struct ApdRuns {
  struct Run {
    int first = 0;
    int repeat = 0;
    size_t begin = 0;  // into dm
    size_t count = 0;
  };
  std::vector<Run> runs;
  std::vector<std::pair<unsigned, unsigned>> dm;
};

ApdRuns apd_runs(const AreaParts& apd, size_t max_intervals) {
  ApdRuns out;
  for (int s = 0; s < apd.stripe_count(); ++s) {
    const size_t begin = out.dm.size();
    for (const Interval& iv : apd.stripe(s)) {
      const long a = std::clamp(static_cast<long>(std::ceil(iv.start_m * 10.0 - 1e-6)), 0L, 65535L);
      const long b = std::clamp(static_cast<long>(std::floor(iv.end_m * 10.0 + 1e-6)), 0L, 65535L);
      if (b > a && out.dm.size() - begin < max_intervals) out.dm.emplace_back(a, b);
    }
    const size_t count = out.dm.size() - begin;
    if (!out.runs.empty()) {
      ApdRuns::Run& last = out.runs.back();
      const auto last_begin = out.dm.begin() + static_cast<long>(last.begin);
      if (last.count == count && last.repeat < 255 &&
          std::equal(last_begin, last_begin + static_cast<long>(count),
                     out.dm.begin() + static_cast<long>(begin))) {
        ++last.repeat;
        out.dm.resize(begin);  // the same list as the run's: kept once
        continue;
      }
    }
    out.runs.push_back({s, 1, begin, count});
  }
  return out;
}

size_t run_bytes(const ApdRuns::Run& run) { return kRunHeaderBytes + kIntervalBytes * run.count; }

void write_run(Writer& w, const ApdRuns& runs, const ApdRuns::Run& run) {
  w.u8(static_cast<unsigned>(run.repeat));
  w.u8(static_cast<unsigned>(run.count));
  for (size_t k = run.begin; k < run.begin + run.count; ++k) {
    w.u16(runs.dm[k].first);
    w.u16(runs.dm[k].second);
  }
}

// Reads runs up to the end of the bytes, stripes first .. first+count-1 exactly; false on
// anything malformed (cut short, an inverted interval, too many or too few stripes). Each run's
// length is checked once and its intervals read straight from the bytes (every agent reads every
// aggregation fragment it hears).
bool read_runs(Reader& r, int first, int count, DecodedRuns* out) {
  const uint8_t* bytes = r.f.data();
  const size_t size = r.f.size();
  size_t pos = r.pos;
  int s = first;
  while (pos < size) {
    if (size - pos < kRunHeaderBytes) return false;
    const int repeat = bytes[pos];
    const size_t n = bytes[pos + 1];
    pos += kRunHeaderBytes;
    if (size - pos < n * kIntervalBytes) return false;
    const size_t begin = out->intervals.size();
    out->intervals.resize(begin + n);
    Interval* iv = out->intervals.data() + begin;
    for (size_t k = 0; k < n; ++k, pos += kIntervalBytes) {
      const unsigned a_dm = bytes[pos] | (unsigned{bytes[pos + 1]} << 8);
      const unsigned b_dm = bytes[pos + 2] | (unsigned{bytes[pos + 3]} << 8);
      iv[k] = {a_dm / 10.0, b_dm / 10.0};
      if (!(iv[k].end_m > iv[k].start_m)) return false;
    }
    if (repeat < 1 || s + repeat > first + count) return false;
    out->spans.push_back({s, repeat, begin, n});
    s += repeat;
  }
  r.pos = pos;
  return s == first + count;
}

}  // namespace

std::optional<FrameFit> fit_frames(size_t channel_max_bytes, std::string* error) {
  if (channel_max_bytes < kMinFrameBytes) {
    if (error) {
      *error = "the radio carries at most " + std::to_string(channel_max_bytes) +
               " bytes a frame; the flock's messages need at least " +
               std::to_string(kMinFrameBytes);
    }
    return std::nullopt;
  }
  FrameFit fit;
  fit.max_frame_bytes = std::min(channel_max_bytes, kMaxAggregateFrameBytes);
  fit.beacon_records = static_cast<int>(
      std::min((std::min(fit.max_frame_bytes, kMaxFrameBytes) - kBeaconHeaderBytes) / kRecordBytes,
               size_t{kMaxRecordsPerBeacon}));
  return fit;
}

std::optional<MessageType> message_type(const Frame& f) {
  if (f.empty()) return std::nullopt;
  if (f[0] == static_cast<uint8_t>(MessageType::kBeacon)) return MessageType::kBeacon;
  if (f[0] == static_cast<uint8_t>(MessageType::kAggregate)) return MessageType::kAggregate;
  return std::nullopt;
}

Frame encode_beacon(const Beacon& b, const RadioFrameOrigin& origin, const FrameFit& fit) {
  Frame f;
  Writer w{f};
  w.u8(static_cast<unsigned>(MessageType::kBeacon));
  w.u8(static_cast<unsigned>(b.self.id));
  w.u8((b.going_home ? kFlagGoingHome : 0u) | (b.self.landed ? kFlagLanded : 0u) |
       ((b.round % kRounds) << kRoundShift) | (b.homebound ? kFlagHomebound : 0u));
  write_state(w, b.self, origin);
  // the records asked for, and no more than fit the frame
  const size_t room =
      (std::clamp(fit.max_frame_bytes, kMinFrameBytes, kMaxFrameBytes) - kBeaconHeaderBytes) /
      kRecordBytes;
  const size_t n =
      std::min({b.records.size(), room,
                static_cast<size_t>(std::clamp(fit.beacon_records, 0, kMaxRecordsPerBeacon))});
  w.u8(static_cast<unsigned>(n));
  for (size_t i = 0; i < n; ++i) {
    const AgentRecord& r = b.records[i];
    w.u8(static_cast<unsigned>(r.id));
    write_state(w, r, origin);
    w.u8(static_cast<unsigned>(std::clamp(r.distance_hops, 0, static_cast<int>(kHopsMask))) |
         (r.landed ? kRecordLanded : 0u));
    w.u16(static_cast<unsigned>(std::clamp(r.age_ms, 0, 65535)));
  }
  return f;
}

std::optional<Beacon> decode_beacon(const Frame& f, const RadioFrameOrigin& origin) {
  Beacon b;
  if (!decode_beacon(f, origin, &b)) return std::nullopt;
  return b;
}

bool decode_beacon(const Frame& f, const RadioFrameOrigin& origin, Beacon* out) {
  if (f.size() < kBeaconHeaderBytes || f.size() > kMaxFrameBytes) return false;
  Reader r{f};
  if (r.u8() != static_cast<unsigned>(MessageType::kBeacon)) return false;
  Beacon& b = *out;
  b.self = AgentRecord{};
  b.records.clear();
  b.self.id = static_cast<int>(r.u8());
  const unsigned flags = r.u8();
  b.going_home = (flags & kFlagGoingHome) != 0;
  b.self.landed = (flags & kFlagLanded) != 0;
  b.round = static_cast<uint8_t>((flags >> kRoundShift) % kRounds);
  b.homebound = (flags & kFlagHomebound) != 0;
  read_state(r, b.self, origin);
  const unsigned n = r.u8();
  if (n > kMaxRecordsPerBeacon || f.size() != kBeaconHeaderBytes + n * kRecordBytes) return false;
  if (b.self.id >= kMaxAgents) return false;
  for (unsigned i = 0; i < n; ++i) {
    AgentRecord a;
    a.id = static_cast<int>(r.u8());
    read_state(r, a, origin);
    const unsigned hops = r.u8();
    a.distance_hops = static_cast<int>(hops & kHopsMask);
    a.landed = (hops & kRecordLanded) != 0;
    a.age_ms = static_cast<int>(r.u16());
    if (a.id >= kMaxAgents) return false;
    b.records.push_back(a);
  }
  if (!r.ok) return false;
  return true;
}

std::vector<Frame> encode_aggregate(const AggregateMessage& m, const FrameFit& fit) {
  // frames of [kMinFrameBytes, kMaxAggregateFrameBytes] (fit_frames' range), so one interval
  // always fits; a run's interval count is a byte
  const size_t max_bytes = std::clamp(fit.max_frame_bytes, kMinFrameBytes, kMaxAggregateFrameBytes);
  const ApdRuns runs = apd_runs(
      m.apd, std::min<size_t>(
                 (max_bytes - kAggregateHeaderBytes - kRunHeaderBytes) / kIntervalBytes, 255));
  // fragments: as many runs as fit the frame after the header (first the cut, since every header
  // carries the number of fragments; then each frame written once)
  struct Fragment {
    size_t run_begin = 0, run_end = 0;
    int first = 0, count = 0;  // stripes
    size_t bytes = kAggregateHeaderBytes;
  };
  std::vector<Fragment> fragments;
  size_t i = 0;
  do {
    Fragment fr;
    fr.run_begin = i;
    fr.first = runs.runs.empty() ? 0 : runs.runs[i].first;
    while (i < runs.runs.size() && fr.bytes + run_bytes(runs.runs[i]) <= max_bytes) {
      fr.bytes += run_bytes(runs.runs[i]);
      fr.count += runs.runs[i].repeat;
      ++i;
    }
    fr.run_end = i;
    fragments.push_back(fr);
  } while (i < runs.runs.size() && fragments.size() < static_cast<size_t>(kMaxFragments));
  std::vector<Frame> out(fragments.size());
  for (size_t k = 0; k < fragments.size(); ++k) {
    const Fragment& fr = fragments[k];
    Frame& f = out[k];
    f.reserve(fr.bytes);
    Writer w{f};
    w.u8(static_cast<unsigned>(MessageType::kAggregate));
    w.u8(static_cast<unsigned>(m.sender));
    w.u8(static_cast<unsigned>(m.origin));
    w.u16(m.query_id);
    w.u16(m.version);
    w.u8(static_cast<unsigned>(k));
    w.u8(static_cast<unsigned>(fragments.size()));
    w.u64(m.responded);
    w.u64(m.acked);
    w.u16(static_cast<unsigned>(fr.first));
    w.u16(static_cast<unsigned>(fr.count));
    for (size_t r = fr.run_begin; r < fr.run_end; ++r) write_run(w, runs, runs.runs[r]);
  }
  return out;
}

void DecodedRuns::apply_to(AreaParts* apd) const {
  for (const Span& sp : spans)
    apd->set_stripes(sp.first, sp.repeat, intervals.data() + sp.begin, sp.count);
}

const AggregateMessage* AggregateReassembler::add(const Frame& f) {
  if (f.size() < kAggregateHeaderBytes || f.size() > kMaxAggregateFrameBytes) return nullptr;
  Reader r{f};
  if (r.u8() != static_cast<unsigned>(MessageType::kAggregate)) return nullptr;
  const int sender = static_cast<int>(r.u8());
  const int origin = static_cast<int>(r.u8());
  const auto query_id = static_cast<uint16_t>(r.u16());
  const auto version = static_cast<uint16_t>(r.u16());
  const int fragment = static_cast<int>(r.u8());
  const int fragments = static_cast<int>(r.u8());
  const uint64_t responded = r.u64();
  const uint64_t acked = r.u64();
  const int first = static_cast<int>(r.u16());
  const int count = static_cast<int>(r.u16());
  if (sender >= kMaxAgents || origin >= kMaxAgents || fragments < 1 || fragments > kMaxFragments ||
      fragment >= fragments || first + count > stripes_) {
    return nullptr;
  }
  // parse the runs before touching any state
  runs_.clear();
  if (!read_runs(r, first, count, &runs_)) return nullptr;

  if (partial_.size() <= static_cast<size_t>(sender))
    partial_.resize(static_cast<size_t>(sender) + 1);
  Partial& p = partial_[static_cast<size_t>(sender)];
  if (p.fragments != fragments || p.origin != origin || p.query_id != query_id ||
      p.version != version) {
    // a new message: as a fresh Partial, in the memory of the last one
    p.origin = origin;
    p.query_id = query_id;
    p.version = version;
    p.fragments = fragments;
    p.received.reset();
    p.received_count = 0;
    p.message.sender = sender;
    p.message.origin = origin;
    p.message.query_id = query_id;
    p.message.version = version;
    if (p.message.apd.stripe_count() == stripes_) {
      p.message.apd.clear();
    } else {
      p.message.apd = AreaParts(stripes_);
    }
  }
  p.message.responded = responded;
  p.message.acked = acked;
  runs_.apply_to(&p.message.apd);
  if (!p.received.test(static_cast<size_t>(fragment))) {
    p.received.set(static_cast<size_t>(fragment));
    ++p.received_count;
  }
  if (p.received_count != fragments) return nullptr;
  p.fragments = 0;  // complete: the sender's next fragment starts a new message
  return &p.message;
}

std::vector<uint8_t> encode_apd(const AreaParts& apd) {
  std::vector<uint8_t> out;
  Writer w{out};
  w.u16(static_cast<unsigned>(apd.stripe_count()));
  const ApdRuns runs = apd_runs(apd, 255);
  for (const ApdRuns::Run& run : runs.runs) write_run(w, runs, run);
  return out;
}

std::optional<AreaParts> decode_apd(const std::vector<uint8_t>& bytes, int stripes) {
  Reader r{bytes};
  if (stripes <= 0 || static_cast<int>(r.u16()) != stripes || !r.ok) return std::nullopt;
  DecodedRuns runs;
  if (!read_runs(r, 0, stripes, &runs)) return std::nullopt;
  AreaParts apd(stripes);
  runs.apply_to(&apd);
  return apd;
}

}  // namespace uavsim::missions::coverage
