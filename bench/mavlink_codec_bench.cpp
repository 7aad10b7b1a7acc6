// MAVLink codec throughput: encoding frames and parsing a stream of them, for a 9-byte (HEARTBEAT)
// and a 28-byte (GLOBAL_POSITION_INT) payload. items/s = frames/s, bytes/s = wire bytes.
#include <benchmark/benchmark.h>

#include <vector>

#include "uavsim/common/mavlink/codec.hpp"
#include "uavsim/common/mavlink/parser.hpp"
#include "uavsim/common/mavlink/generated/messages.hpp"

namespace mav = uavsim::common::mavlink;

namespace {

constexpr int kFramesPerStream = 1000;

mav::msg::Heartbeat make_heartbeat() {
  mav::msg::Heartbeat m;
  m.type = 2;
  m.autopilot = 3;
  m.base_mode = 217;
  m.custom_mode = 4;
  m.system_status = 4;
  return m;
}

mav::msg::GlobalPositionInt make_position() {
  mav::msg::GlobalPositionInt m;
  m.time_boot_ms = 123456;
  m.lat = 473977420;
  m.lon = 85455940;
  m.alt = 488000;
  m.relative_alt = 10000;
  m.vx = 100;
  m.vy = -200;
  m.vz = 30;
  m.hdg = 9000;
  return m;
}

mav::FrameHeader header(bool sign) {
  mav::FrameHeader h;
  if (sign) h.signing = mav::SigningParams{mav::SecretKey{}, 1, 1000};
  return h;
}

template <class Msg>
void encode_bench(benchmark::State& state, const Msg& msg, bool sign) {
  mav::FrameHeader h = header(sign);
  std::array<std::uint8_t, mav::kMaxFrameLen> out;
  std::size_t bytes = 0;
  for (auto _ : state) {
    ++h.seq;
    const std::size_t n = mav::encode_into(h, msg, out);
    benchmark::DoNotOptimize(out.data());
    bytes += n;
  }
  state.SetItemsProcessed(state.iterations());
  state.SetBytesProcessed(static_cast<std::int64_t>(bytes));
}

template <class Msg>
void parse_bench(benchmark::State& state, const Msg& msg, bool sign) {
  // a stream of back-to-back frames, parsed in 4 KiB chunks as a socket read would deliver them
  std::vector<std::uint8_t> stream;
  mav::FrameHeader h = header(sign);
  for (int i = 0; i < kFramesPerStream; ++i) {
    ++h.seq;
    if (h.signing) h.signing->timestamp_10us += 1;  // signed timestamps must increase
    const mav::EncodedFrame f = mav::encode(h, msg);
    stream.insert(stream.end(), f.view().begin(), f.view().end());
  }
  mav::ParserConfig config;
  if (sign) config.signing_key = mav::SecretKey{};
  std::size_t frames = 0;
  constexpr std::size_t kChunk = 4096;
  for (auto _ : state) {
    // a fresh parser per pass: replaying the same signed stream would (rightly) be refused
    mav::Parser parser(config);
    for (std::size_t i = 0; i < stream.size(); i += kChunk) {
      parser.feed(
          std::span<const std::uint8_t>(stream).subspan(i, std::min(kChunk, stream.size() - i)),
          [&](const mav::Frame& f) {
            benchmark::DoNotOptimize(Msg::decode(f.payload.data()));
            ++frames;
          });
    }
  }
  if (frames != static_cast<std::size_t>(state.iterations()) * kFramesPerStream) {
    state.SkipWithError("parser lost frames");
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(frames));
  state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations() * stream.size()));
}

void BM_EncodeHeartbeat(benchmark::State& s) { encode_bench(s, make_heartbeat(), false); }
void BM_EncodeGlobalPositionInt(benchmark::State& s) { encode_bench(s, make_position(), false); }
void BM_EncodeGlobalPositionIntSigned(benchmark::State& s) {
  encode_bench(s, make_position(), true);
}
void BM_ParseHeartbeat(benchmark::State& s) { parse_bench(s, make_heartbeat(), false); }
void BM_ParseGlobalPositionInt(benchmark::State& s) { parse_bench(s, make_position(), false); }
void BM_ParseGlobalPositionIntSigned(benchmark::State& s) { parse_bench(s, make_position(), true); }

}  // namespace

BENCHMARK(BM_EncodeHeartbeat);
BENCHMARK(BM_EncodeGlobalPositionInt);
BENCHMARK(BM_EncodeGlobalPositionIntSigned);
BENCHMARK(BM_ParseHeartbeat);
BENCHMARK(BM_ParseGlobalPositionInt);
BENCHMARK(BM_ParseGlobalPositionIntSigned);

BENCHMARK_MAIN();
