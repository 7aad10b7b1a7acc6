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
// less is claimed, never more).
struct Run {
  int first = 0;
  int repeat = 0;
  std::vector<std::pair<unsigned, unsigned>> dm;
};

std::vector<Run> apd_runs(const AreaParts& apd, size_t max_intervals) {
  std::vector<Run> runs;
  for (int s = 0; s < apd.stripe_count(); ++s) {
    std::vector<std::pair<unsigned, unsigned>> dm;
    for (const Interval& iv : apd.stripe(s)) {
      const long a = std::clamp(static_cast<long>(std::ceil(iv.start_m * 10.0 - 1e-6)), 0L, 65535L);
      const long b = std::clamp(static_cast<long>(std::floor(iv.end_m * 10.0 + 1e-6)), 0L, 65535L);
      if (b > a && dm.size() < max_intervals) dm.emplace_back(a, b);
    }
    if (!runs.empty() && runs.back().dm == dm && runs.back().repeat < 255) {
      ++runs.back().repeat;
    } else {
      runs.push_back({s, 1, std::move(dm)});
    }
  }
  return runs;
}

void write_run(Writer& w, const Run& run) {
  w.u8(static_cast<unsigned>(run.repeat));
  w.u8(static_cast<unsigned>(run.dm.size()));
  for (const auto& [a, b] : run.dm) {
    w.u16(a);
    w.u16(b);
  }
}

// The runs of one message, decoded: every run's intervals in one flat list, so that decoding a
// message allocates twice however many stripes it carries (every agent decodes every aggregate
// frame it hears).
struct DecodedRuns {
  struct Span {
    int first = 0;   // stripe
    int repeat = 0;  // stripes first .. first+repeat-1 share the intervals
    size_t begin = 0;
    size_t count = 0;
  };
  std::vector<Span> spans;
  std::vector<Interval> intervals;

  void apply_to(AreaParts* apd) const {
    for (const Span& sp : spans)
      for (int k = 0; k < sp.repeat; ++k)
        apd->set_stripe(sp.first + k, intervals.data() + sp.begin, sp.count);
  }
};

// Reads runs up to the end of the bytes, stripes first .. first+count-1 exactly; false on
// anything malformed (an inverted interval, too many or too few stripes).
bool read_runs(Reader& r, int first, int count, DecodedRuns* out) {
  int s = first;
  while (r.pos < r.f.size()) {
    const int repeat = static_cast<int>(r.u8());
    const unsigned n = r.u8();
    const size_t begin = out->intervals.size();
    for (unsigned k = 0; k < n; ++k) {
      const double a = r.u16() / 10.0, b = r.u16() / 10.0;
      if (!(b > a)) return false;
      out->intervals.push_back({a, b});
    }
    if (!r.ok || repeat < 1 || s + repeat > first + count) return false;
    out->spans.push_back({s, repeat, begin, n});
    s += repeat;
  }
  return r.ok && s == first + count;
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
  if (f.size() < kBeaconHeaderBytes || f.size() > kMaxFrameBytes) return std::nullopt;
  Reader r{f};
  if (r.u8() != static_cast<unsigned>(MessageType::kBeacon)) return std::nullopt;
  Beacon b;
  b.self.id = static_cast<int>(r.u8());
  const unsigned flags = r.u8();
  b.going_home = (flags & kFlagGoingHome) != 0;
  b.self.landed = (flags & kFlagLanded) != 0;
  b.round = static_cast<uint8_t>((flags >> kRoundShift) % kRounds);
  b.homebound = (flags & kFlagHomebound) != 0;
  read_state(r, b.self, origin);
  const unsigned n = r.u8();
  if (n > kMaxRecordsPerBeacon || f.size() != kBeaconHeaderBytes + n * kRecordBytes)
    return std::nullopt;
  if (b.self.id >= kMaxAgents) return std::nullopt;
  for (unsigned i = 0; i < n; ++i) {
    AgentRecord a;
    a.id = static_cast<int>(r.u8());
    read_state(r, a, origin);
    const unsigned hops = r.u8();
    a.distance_hops = static_cast<int>(hops & kHopsMask);
    a.landed = (hops & kRecordLanded) != 0;
    a.age_ms = static_cast<int>(r.u16());
    if (a.id >= kMaxAgents) return std::nullopt;
    b.records.push_back(a);
  }
  if (!r.ok) return std::nullopt;
  return b;
}

std::vector<Frame> encode_aggregate(const AggregateMessage& m, const FrameFit& fit) {
  // frames of [kMinFrameBytes, kMaxAggregateFrameBytes] (fit_frames' range), so one interval
  // always fits; a run's interval count is a byte
  const size_t max_bytes = std::clamp(fit.max_frame_bytes, kMinFrameBytes, kMaxAggregateFrameBytes);
  const std::vector<Run> runs = apd_runs(
      m.apd, std::min<size_t>(
                 (max_bytes - kAggregateHeaderBytes - kRunHeaderBytes) / kIntervalBytes, 255));
  // fragments: as many runs as fit the frame after the header
  std::vector<Frame> frames;
  std::vector<std::pair<int, int>> stripe_range;  // first, count of each fragment
  size_t i = 0;
  do {
    Frame body;
    Writer w{body};
    const int first = runs.empty() ? 0 : runs[i].first;
    int count = 0;
    while (i < runs.size() && kAggregateHeaderBytes + body.size() + kRunHeaderBytes +
                                      kIntervalBytes * runs[i].dm.size() <=
                                  max_bytes) {
      write_run(w, runs[i]);
      count += runs[i].repeat;
      ++i;
    }
    frames.push_back(std::move(body));
    stripe_range.emplace_back(first, count);
  } while (i < runs.size() && frames.size() < static_cast<size_t>(kMaxFragments));
  // headers
  std::vector<Frame> out;
  for (size_t k = 0; k < frames.size(); ++k) {
    Frame f;
    Writer w{f};
    w.u8(static_cast<unsigned>(MessageType::kAggregate));
    w.u8(static_cast<unsigned>(m.sender));
    w.u8(static_cast<unsigned>(m.origin));
    w.u16(m.query_id);
    w.u16(m.version);
    w.u8(static_cast<unsigned>(k));
    w.u8(static_cast<unsigned>(frames.size()));
    w.u64(m.responded);
    w.u64(m.acked);
    w.u16(static_cast<unsigned>(stripe_range[k].first));
    w.u16(static_cast<unsigned>(stripe_range[k].second));
    f.insert(f.end(), frames[k].begin(), frames[k].end());
    out.push_back(std::move(f));
  }
  return out;
}

std::optional<AggregateMessage> AggregateReassembler::add(const Frame& f) {
  if (f.size() < kAggregateHeaderBytes || f.size() > kMaxAggregateFrameBytes) return std::nullopt;
  Reader r{f};
  if (r.u8() != static_cast<unsigned>(MessageType::kAggregate)) return std::nullopt;
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
    return std::nullopt;
  }
  // parse the runs before touching any state
  DecodedRuns runs;
  if (!read_runs(r, first, count, &runs)) return std::nullopt;

  Partial& p = partial_[sender];
  if (p.fragments != fragments || p.origin != origin || p.query_id != query_id ||
      p.version != version) {
    p = Partial{};
    p.origin = origin;
    p.query_id = query_id;
    p.version = version;
    p.fragments = fragments;
    p.message.sender = sender;
    p.message.origin = origin;
    p.message.query_id = query_id;
    p.message.version = version;
    p.message.apd = AreaParts(stripes_);
  }
  p.message.responded = responded;
  p.message.acked = acked;
  runs.apply_to(&p.message.apd);
  p.received.set(static_cast<size_t>(fragment));
  if (p.received.count() != static_cast<size_t>(fragments)) return std::nullopt;
  AggregateMessage done = std::move(p.message);
  partial_.erase(sender);
  return done;
}

std::vector<uint8_t> encode_apd(const AreaParts& apd) {
  std::vector<uint8_t> out;
  Writer w{out};
  w.u16(static_cast<unsigned>(apd.stripe_count()));
  for (const Run& run : apd_runs(apd, 255)) write_run(w, run);
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
