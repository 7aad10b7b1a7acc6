// A2aRadio against uavsim-server (a subprocess) on three quads 4 m apart: frames ride on the loop's
// lockstep connection, so a frame is received at the first tick at or after its arrival (docs/
// protocol.md "Radio"), never earlier, with its sender and bytes.
#include "uavsim/client/radio.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <regex>
#include <string>
#include <vector>

#include "server_process.hpp"
#include "uavsim/client/event_loop.hpp"
#include "uavsim/client/sim_connection.hpp"

namespace uavsim::client::testing {
namespace {

constexpr double kPeriod_s = 0.02;  // the loop's lockstep period
constexpr double kTimeTol_s = 1e-6;

// the three quads, without cameras
const std::string kThreeQuads = std::string(UAVSIM_TEST_DATA_DIR) + "/worlds/three_quads.xml";

std::vector<std::uint8_t> frame(std::size_t n, std::uint8_t first) {
  std::vector<std::uint8_t> f(n);
  for (std::size_t i = 0; i < n; ++i) f[i] = static_cast<std::uint8_t>(first + i);
  return f;
}

// A lockstep loop on the server (null, with the test's failure, when either cannot start).
std::unique_ptr<EventLoop> lockstep_loop(const ServerProcess& server) {
  EXPECT_GT(server.api_port(), 0) << server.output();
  if (server.api_port() <= 0) return nullptr;
  auto l = EventLoop::create(LoopConfig::lockstep("127.0.0.1", server.api_port(), kPeriod_s));
  EXPECT_TRUE(l) << l.message();
  return l ? std::move(*l) : nullptr;
}

TEST(A2aRadio, AFrameIsReceivedAtTheFirstTickAtOrAfterItsArrival) {
  ServerProcess server(kThreeQuads, {"--no-cameras"});
  auto l = lockstep_loop(server);
  ASSERT_TRUE(l);
  EventLoop& loop = *l;
  std::vector<std::unique_ptr<A2aRadio>> radio;
  for (int v = 0; v < 3; ++v) {
    auto r = A2aRadio::open(loop, v);
    ASSERT_TRUE(r) << r.message();
    radio.push_back(std::move(*r));
  }
  ASSERT_TRUE(loop.run_for(0.1));
  for (auto& r : radio) EXPECT_TRUE(r->take_received().empty());

  // sent at tick t0: 40 bytes take (40 + 6) * 8 / 250 kbit/s = 1.5 ms on air, so they arrive
  // between t0 and the next tick, t0 + 0.02
  const double t0 = loop.now();
  const auto data = frame(40, 7);
  ASSERT_TRUE(radio[0]->send(data));
  EXPECT_TRUE(radio[1]->take_received().empty());  // not before the tick after its arrival
  ASSERT_TRUE(loop.run_for(kPeriod_s));
  EXPECT_NEAR(loop.now(), t0 + kPeriod_s, kTimeTol_s);
  for (int v : {1, 2}) {
    const auto got = radio[static_cast<size_t>(v)]->take_received();
    ASSERT_EQ(got.size(), 1u) << "vehicle " << v;
    EXPECT_EQ(got[0].from, 0);
    EXPECT_TRUE(got[0].broadcast);
    EXPECT_EQ(got[0].data, data);
    EXPECT_GT(got[0].time_s, t0 + 0.0014);
    EXPECT_LE(got[0].time_s, loop.now() + kTimeTol_s);
  }
  EXPECT_TRUE(radio[0]->take_received().empty());  // not to itself
  EXPECT_EQ(radio[0]->counters().sent, 1u);
  EXPECT_EQ(radio[1]->counters().received, 1u);
}

// Pipelined lockstep (one-tick compute latency): what the program sends during tick t0's work goes
// on air at the next tick, so it is heard one tick later than above, and the loop answered tick t0
// before the work (the simulation stepped on meanwhile).
TEST(A2aRadio, PipelinedAFrameSentDuringATickGoesOnAirAtTheNext) {
  ServerProcess server(kThreeQuads, {"--no-cameras"});
  auto l = lockstep_loop(server);
  ASSERT_TRUE(l);
  EventLoop& loop = *l;
  auto r0 = A2aRadio::open(loop, 0), r1 = A2aRadio::open(loop, 1);
  ASSERT_TRUE(r0 && r1) << (r0 ? r1.message() : r0.message());
  loop.set_lockstep_pipelined(true);
  ASSERT_TRUE(loop.run_for(0.1));
  const double t0 = loop.now();
  const auto data = frame(40, 9);
  ASSERT_TRUE((*r0)->send(data));
  ASSERT_TRUE(loop.run_for(kPeriod_s));  // tick t0 + p: the frame goes on air now (1.5 ms)
  EXPECT_TRUE((*r1)->take_received().empty());
  ASSERT_TRUE(loop.run_for(kPeriod_s));  // tick t0 + 2p: heard
  const auto got = (*r1)->take_received();
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].data, data);
  EXPECT_GT(got[0].time_s, t0 + kPeriod_s + 0.0014);
  EXPECT_LE(got[0].time_s, t0 + 2 * kPeriod_s + kTimeTol_s);
}

TEST(A2aRadio, UnicastReachesOnlyTheAddressee) {
  ServerProcess server(kThreeQuads, {"--no-cameras"});
  auto l = lockstep_loop(server);
  ASSERT_TRUE(l);
  EventLoop& loop = *l;
  auto r0 = A2aRadio::open(loop, 0), r1 = A2aRadio::open(loop, 1), r2 = A2aRadio::open(loop, 2);
  ASSERT_TRUE(r0 && r1 && r2);
  ASSERT_TRUE((*r1)->send(frame(127, 1), 2));  // a full 802.15.4 frame
  ASSERT_TRUE(loop.run_for(kPeriod_s));
  const auto to2 = (*r2)->take_received();
  ASSERT_EQ(to2.size(), 1u);
  EXPECT_EQ(to2[0].from, 1);
  EXPECT_FALSE(to2[0].broadcast);
  EXPECT_EQ(to2[0].data.size(), 127u);
  EXPECT_TRUE((*r0)->take_received().empty());
}

TEST(A2aRadio, CountsTheSimulatorsRefusals) {
  // a frame past the sender's queue of 256 is refused with queue_full; the radio counts those
  ServerProcess server(kThreeQuads, {"--no-cameras"});
  auto l = lockstep_loop(server);
  ASSERT_TRUE(l);
  EventLoop& loop = *l;
  auto r0 = A2aRadio::open(loop, 0), r1 = A2aRadio::open(loop, 1);
  ASSERT_TRUE(r0 && r1);
  constexpr int kQueueFrames = 256, kSent = 300;
  for (int i = 0; i < kSent; ++i) ASSERT_TRUE((*r0)->send(frame(100, static_cast<uint8_t>(i))));
  ASSERT_TRUE(loop.run_for(kPeriod_s));
  EXPECT_EQ((*r0)->counters().sent, static_cast<uint64_t>(kSent));
  EXPECT_EQ((*r0)->counters().refused, static_cast<uint64_t>(kSent - kQueueFrames));
  // the queued ones go on air one after the other: the first has arrived at the next tick
  EXPECT_FALSE((*r1)->take_received().empty());
}

TEST(A2aRadio, RefusesFramesOutside1To127BytesAndTheHostClock) {
  ServerProcess server(kThreeQuads, {"--no-cameras"});
  auto l = lockstep_loop(server);
  ASSERT_TRUE(l);
  auto r = A2aRadio::open(*l, 0);
  ASSERT_TRUE(r) << r.message();
  const auto big = (*r)->send(frame(128, 0));
  ASSERT_FALSE(big);
  EXPECT_EQ(big.code(), Error::kInvalidArgument);
  const auto empty = (*r)->send({});
  ASSERT_FALSE(empty);
  EXPECT_EQ(empty.code(), Error::kInvalidArgument);
  const auto unknown = A2aRadio::open(*l, 3);  // three_quads has vehicles 0-2
  ASSERT_FALSE(unknown);
  EXPECT_EQ(unknown.code(), Error::kDenied);

  auto host = EventLoop::create(LoopConfig::host());
  ASSERT_TRUE(host);
  const auto on_host = A2aRadio::open(**host, 0);
  ASSERT_FALSE(on_host);
  EXPECT_EQ(on_host.code(), Error::kUnsupported);
}

TEST(A2aRadio, TakesItsFrameSizeFromTheServersChannel) {
  {
    ServerProcess server(kThreeQuads, {"--no-cameras"});
    auto l = lockstep_loop(server);
    ASSERT_TRUE(l);
    auto r = A2aRadio::open(*l, 0);
    ASSERT_TRUE(r) << r.message();
    EXPECT_EQ((*r)->max_frame_bytes(), 127u);
  }
  // the ns3 backend: 116 bytes (127 less a short-addressed MAC header and FCS), and a frame goes
  // through ns-3 to the other quads
#ifndef UAVSIM_HAS_NS3
  GTEST_SKIP() << "built without ns-3 (scripts/install_deps.sh installs it)";
#endif
  ServerProcess server(kThreeQuads, {"--no-cameras", "--radio-backend", "ns3"});
  auto l = lockstep_loop(server);
  ASSERT_TRUE(l);
  EventLoop& loop = *l;
  auto r0 = A2aRadio::open(loop, 0), r1 = A2aRadio::open(loop, 1);
  ASSERT_TRUE(r0 && r1);
  EXPECT_EQ((*r0)->max_frame_bytes(), 116u);
  const auto big = (*r0)->send(frame(117, 0));
  ASSERT_FALSE(big);
  EXPECT_EQ(big.code(), Error::kInvalidArgument);
  ASSERT_TRUE((*r0)->send(frame(116, 3)));
  ASSERT_TRUE(loop.run_for(2 * kPeriod_s));
  const auto got = (*r1)->take_received();
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].data, frame(116, 3));
}

TEST(A2aRadio, CarriesFramesOf1500BytesOnNs3s80211) {
#ifndef UAVSIM_HAS_NS3
  GTEST_SKIP() << "built without ns-3 (scripts/install_deps.sh installs it)";
#endif
  ServerProcess server(kThreeQuads, {"--no-cameras", "--radio-backend", "ns3"});
  ASSERT_GT(server.api_port(), 0) << server.output();
  {
    auto api = SimConnection::connect("127.0.0.1", static_cast<std::uint16_t>(server.api_port()));
    ASSERT_TRUE(api) << api.message();
    ASSERT_TRUE((*api)->request({{"op", "radio_config"}, {"technology", "802.11"}}));
  }
  auto l = lockstep_loop(server);
  ASSERT_TRUE(l);
  EventLoop& loop = *l;
  auto r0 = A2aRadio::open(loop, 0), r1 = A2aRadio::open(loop, 1);
  ASSERT_TRUE(r0 && r1);
  EXPECT_EQ((*r0)->max_frame_bytes(), 1500u);
  EXPECT_EQ((*r0)->send(frame(1501, 0)).code(), Error::kInvalidArgument);
  ASSERT_TRUE((*r0)->send(frame(1500, 5)));
  ASSERT_TRUE(loop.run_for(3 * kPeriod_s));
  const auto got = (*r1)->take_received();
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].data, frame(1500, 5));
}

}  // namespace
}  // namespace uavsim::client::testing
