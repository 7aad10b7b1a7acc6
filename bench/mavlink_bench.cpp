// MAVLink endpoint benchmarks over loopback (Google Benchmark; figures, not a gate):
//   BM_TelemetryThroughput/N/hover:H  N lean quads on a 4 m grid (bench_fleet.hpp), parked on the ground
//                             (H = 0) or hovering in formation 5 m up (H = 1), one client each, every stream
//                             group at 50 Hz: frames delivered to the clients per wall second while the loop
//                             steps as fast as it can; x_real_time, flying. shards:S = the vehicles in S
//                             physics shards on one thread (S = 2: two models of 50 stay in cache).
//   BM_CommandAckLatency/N/R  N vehicles, the loop on its own thread at R x real time (0 = as fast as
//                             possible); one client on vehicle 0: COMMAND_LONG -> COMMAND_ACK round trip.
#include <benchmark/benchmark.h>
#include <poll.h>
#include <arpa/inet.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "bench_fleet.hpp"
#include "uavsim/common/mavlink/codec.hpp"
#include "uavsim/common/mavlink/parser.hpp"
#include "mavlink/endpoint.hpp"
#include "uavsim/common/mavlink/generated/messages.hpp"
#include "physics/world.hpp"
#include "sim/runner.hpp"
#include "sim/simulation.hpp"

namespace mav = uavsim::server::mavlink;
namespace cm = uavsim::common::mavlink;
namespace sim = uavsim::server::sim;
namespace physics = uavsim::server::physics;

namespace {

// n lean quads on a 4 m grid, parked on the ground; with hover, all launched into a formation 5 m up; in
// `shards` physics shards stepped by one thread
std::unique_ptr<sim::Simulation> make_grid_sim(int n, bool hover = false, int shards = 1) {
  auto s = std::make_unique<sim::Simulation>(
      uavsim::bench::load(n, 0.0, "lean", physics::ShardOptions{shards, 1}), sim::SimConfig{});
  if (hover) {
    while (s->time_s() < 20.0 && !s->fc(0).prearm_ok()) s->step();
    uavsim::bench::launch_all(*s);
  }
  return s;
}

int connect_to(std::uint16_t port) {
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in sa{};
  sa.sin_family = AF_INET;
  sa.sin_port = htons(port);
  inet_pton(AF_INET, "127.0.0.1", &sa.sin_addr);
  connect(fd, reinterpret_cast<sockaddr*>(&sa), sizeof(sa));
  const int one = 1;
  setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof(one));
  return fd;
}

template <class Msg>
void send_msg(int fd, const Msg& m) {
  const cm::EncodedFrame f = cm::encode(cm::FrameHeader{255, 190, 0, cm::Version::kV2, std::nullopt}, m);
  [[maybe_unused]] const auto n = ::send(fd, f.bytes.data(), f.size, MSG_NOSIGNAL);
}

void BM_TelemetryThroughput(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const bool hover = state.range(1) != 0;
  auto s = make_grid_sim(n, hover, static_cast<int>(state.range(2)));
  mav::EndpointConfig c;
  c.base_port = 0;
  mav::MavlinkServer server(*s, c);
  server.schedule(s->schedule());  // without it the endpoints never handle a message nor send telemetry
  std::vector<int> fds;
  for (int i = 0; i < n; ++i) {
    fds.push_back(connect_to(server.port(i)));
    cm::msg::RequestDataStream r;
    r.target_system = static_cast<std::uint8_t>(i + 1);
    r.req_stream_id = 0;
    r.req_message_rate = 50;
    r.start_stop = 1;
    send_msg(fds.back(), r);
  }
  // a reader thread per benchmark drains every socket and counts frames
  std::atomic<bool> stop{false};
  std::atomic<std::uint64_t> frames{0};
  std::thread reader([&] {
    std::vector<cm::Parser> parsers(fds.size());
    std::vector<pollfd> pfds;
    for (int fd : fds) pfds.push_back({fd, POLLIN, 0});
    std::vector<std::uint8_t> buf(1 << 16);
    while (!stop.load()) {
      if (poll(pfds.data(), pfds.size(), 20) <= 0) continue;
      for (std::size_t k = 0; k < pfds.size(); ++k) {
        if (!(pfds[k].revents & POLLIN)) continue;
        const ssize_t r = recv(pfds[k].fd, buf.data(), buf.size(), MSG_DONTWAIT);
        if (r <= 0) continue;
        std::uint64_t got = 0;
        parsers[k].feed({buf.data(), static_cast<std::size_t>(r)}, [&](const cm::Frame&) { ++got; });
        frames.fetch_add(got);
      }
    }
  });
  s->run_until(1.0);  // connect + rate requests handled, warm-up
  const std::uint64_t frames_start = frames.load();
  const double sim_start = s->time_s();
  const auto wall_start = std::chrono::steady_clock::now();
  for (auto _ : state) s->run_until(s->time_s() + 1.0);
  const double wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  std::this_thread::sleep_for(std::chrono::milliseconds(100));  // let the last frames arrive (reporting only)
  stop = true;
  reader.join();
  std::uint64_t sent = 0, dropped = 0;
  for (int i = 0; i < n; ++i) {
    sent += server.stats(i).frames_sent;
    dropped += server.stats(i).frames_dropped_full;
  }
  const double received = static_cast<double>(frames.load() - frames_start);
  state.counters["frames_per_s"] = received / wall_s;
  state.counters["x_real_time"] = (s->time_s() - sim_start) / wall_s;
  state.counters["dropped_frames"] = static_cast<double>(dropped);
  state.counters["sent_frames"] = static_cast<double>(sent);
  state.counters["flying"] = static_cast<double>(uavsim::bench::flying(*s));
  state.SetItemsProcessed(static_cast<int64_t>(received));
  for (int fd : fds) close(fd);
}
BENCHMARK(BM_TelemetryThroughput)
    ->ArgNames({"", "hover", "shards"})
    ->Args({1, 0, 1})
    ->Args({10, 0, 1})
    ->Args({100, 0, 1})
    ->Args({10, 1, 1})
    ->Args({100, 1, 1})
    ->Args({100, 1, 2})
    ->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_CommandAckLatency(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const double rate = static_cast<double>(state.range(1));
  auto s = make_grid_sim(n);
  mav::EndpointConfig c;
  c.base_port = 0;
  mav::MavlinkServer server(*s, c);
  server.schedule(s->schedule());  // without it the endpoints never handle a message nor send telemetry
  const int fd = connect_to(server.port(0));
  // only the acks matter: stop the streams of this client
  cm::msg::RequestDataStream r;
  r.target_system = 1;
  r.req_stream_id = 0;
  r.start_stop = 0;
  send_msg(fd, r);
  sim::Runner runner(*s, rate);
  std::thread loop([&] { runner.run_until(1e9); });
  cm::Parser parser;
  std::vector<std::uint8_t> buf(1 << 16);
  cm::msg::CommandLong cmd;
  cmd.target_system = 1;
  cmd.command = 31000;  // unknown: UNSUPPORTED, no side effects
  for (auto _ : state) {
    send_msg(fd, cmd);
    bool acked = false;
    while (!acked) {
      const ssize_t got = recv(fd, buf.data(), buf.size(), 0);
      if (got <= 0) break;
      parser.feed({buf.data(), static_cast<std::size_t>(got)}, [&](const cm::Frame& f) {
        acked = acked || f.msgid == cm::msg::CommandAck::kId;
      });
    }
  }
  runner.stop();
  loop.join();
  close(fd);
}
BENCHMARK(BM_CommandAckLatency)
    ->Args({1, 0})->Args({10, 0})->Args({100, 0})->Args({1, 1})->Args({100, 1})
    ->Unit(benchmark::kMicrosecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
