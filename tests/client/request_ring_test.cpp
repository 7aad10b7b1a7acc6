// A client's request ring (docs/protocol.md, "Shared-memory stream"; server: api/request_ring.hpp)
// against the real server in process: every request goes through the ring in order, a binary done
// ends its tick without a reply, a refused binary request is answered under its tag, a malformed
// one is answered and the connection stays, and a client that writes what a client may not write
// into its ring is dropped while the others tick on.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "loop_services.hpp"
#include "raw_shm_client.hpp"
#include "sim_channel.hpp"
#include "sim_harness.hpp"
#include "uavsim/client/event_loop.hpp"
#include "uavsim/common/shm_requests.hpp"

namespace uavsim::client::testing {
namespace {

namespace shm = common::shm;
using Lines = std::vector<std::string>;

// A raw lockstep client (period 20 ms) with a request ring, joined through it at sim time 0: one
// wake-up brings the join's reply and its first tick.
void join_with_request_ring(RawShmClient& c) {
  const Json offer = c.tcp_request({{"op", "lockstep_shm"}, {"requests", true}});
  ASSERT_EQ(offer["ok"], true) << offer;
  ASSERT_EQ(offer["result"].value("request_ring_bytes", 0), 2 << 20) << offer;
  ASSERT_TRUE(c.take_stream(offer["result"]));
  ASSERT_TRUE(c.has_request_ring());
  c.send_on_ring({{"op", "lockstep_join"}, {"period_s", 0.02}, {"id", "join"}});
  ASSERT_EQ(c.sleep_until_woken(), (Lines{"woken 1", "join ok", "tick 0"}));
}

std::vector<std::uint8_t> done_record(std::int64_t tick, std::uint32_t tag = 0) {
  shm::DoneRecord d;
  d.tag = tag;
  d.quiet = true;
  d.tick = tick;
  std::vector<std::uint8_t> out;
  shm::encode_done(d, &out);
  return out;
}

TEST(RequestRing, TheOpChecksItsFieldsAndGivesNoneUnasked) {
  SimServer server;
  RawShmClient c(server.api_port());
  for (const Json& bad : {Json{{"requests", 1}}, Json{{"requests", "yes"}},
                          Json{{"requests", true}, {"request_ring_bytes", 1000}},
                          Json{{"requests", true}, {"request_ring_bytes", 1u << 29}}}) {
    Json request = bad;
    request["op"] = "lockstep_shm";
    const Json r = c.tcp_request(request);
    EXPECT_EQ(r["error"]["code"], "bad_field") << bad << " " << r;
  }
  const Json offer = c.tcp_request({{"op", "lockstep_shm"}, {"requests", false}});
  ASSERT_EQ(offer["ok"], true) << offer;
  EXPECT_FALSE(offer["result"].contains("request_ring_bytes")) << offer;
  ASSERT_TRUE(c.take_stream(offer["result"]));
  EXPECT_FALSE(c.has_request_ring());
}

TEST(RequestRing, RequestsGoThroughItInOrderAndABinaryDoneEndsItsTickUnanswered) {
  SimServer server;
  RawShmClient a(server.api_port());
  ASSERT_NO_FATAL_FAILURE(join_with_request_ring(a));
  ApiClient api(server.api_port());
  ASSERT_EQ(api.request({{"op", "resume"}}).value("ok", false), true);
  for (std::int64_t tick = 0; tick < 5; ++tick) {
    // requests as lines, then the binary done, in one burst (one wake-up of the server): the
    // lines' replies, the tick, nothing for the done
    a.send_on_ring({{"op", "status"}, {"id", "1"}}, /*deferred=*/true);
    a.send_on_ring({{"op", "status"}, {"id", "2"}}, /*deferred=*/true);
    a.send_record(shm::RecordType::kDone, done_record(tick), /*deferred=*/true);
    a.flush();
    EXPECT_EQ(a.sleep_until_woken(),
              (Lines{"woken 1", "1 ok", "2 ok", "tick " + std::to_string(tick + 1)}));
  }
  EXPECT_EQ(api.request({{"op", "status"}})["result"]["lockstep_clients"], 1);
}

TEST(RequestRing, ARefusedBinaryRequestIsAnsweredUnderItsTagAndAMalformedOneToo) {
  SimServer server;  // no radio: radio_send is an unknown op here
  RawShmClient a(server.api_port());
  ASSERT_NO_FATAL_FAILURE(join_with_request_ring(a));
  std::vector<std::uint8_t> send;
  const std::uint8_t frame[] = {1, 2, 3};
  shm::encode_radio_send(5, 0, -1, frame, &send);
  a.send_record(shm::RecordType::kRadioSend, send);
  EXPECT_EQ(a.sleep_until_woken(), (Lines{"woken 1", "b5 unknown_op"}));
  // a done of a tick that is not the client's (tag 0: no id)
  a.send_record(shm::RecordType::kDone, done_record(7));
  const Lines refused = a.sleep_until_woken();
  ASSERT_EQ(refused.size(), 2u);
  EXPECT_EQ(refused[1].rfind("null ", 0), 0u) << refused[1];
  EXPECT_NE(refused[1], "null ok");
  // cut short: bad_request, and the connection stays
  std::vector<std::uint8_t> cut = done_record(0, 3);
  cut.resize(cut.size() - 1);
  a.send_record(shm::RecordType::kDone, cut);
  EXPECT_EQ(a.sleep_until_woken(), (Lines{"woken 1", "null bad_request"}));
  a.send_on_ring({{"op", "status"}, {"id", "after"}});
  EXPECT_EQ(a.sleep_until_woken(), (Lines{"woken 1", "after ok"}));
}

// A record a client may not send (a tick) in its request ring: the client is dropped, its stream
// hangs up, and the other lockstep client (client_cpp's loop, on a request ring of its own) ticks
// on.
TEST(RequestRing, AClientThatWritesATickIntoItIsDroppedAndTheOthersTickOn) {
  SimServer server;
  auto l = EventLoop::create(LoopConfig::lockstep("127.0.0.1", server.api_port(), 0.02));
  ASSERT_TRUE(l) << l.message();
  ASSERT_TRUE(LoopServices(**l).sim_channel()->has_request_ring());
  RawShmClient hostile(server.api_port());
  ASSERT_NO_FATAL_FAILURE(join_with_request_ring(hostile));
  ApiClient api(server.api_port());
  ASSERT_EQ(api.request({{"op", "status"}})["result"]["lockstep_clients"], 2);
  const std::vector<std::uint8_t> tick = shm::encode_tick_head(1, 0.02, 0);
  hostile.send_record(shm::RecordType::kTick, tick);
  EXPECT_TRUE(hostile.hung_up());
  ASSERT_EQ(api.request({{"op", "resume"}}).value("ok", false), true);
  EventLoop& loop = **l;
  const double before = loop.now();
  ASSERT_TRUE(loop.run_for(1.0));
  EXPECT_GE(loop.now(), before + 1.0 - 1e-9);
  EXPECT_EQ(api.request({{"op", "status"}})["result"]["lockstep_clients"], 1);
}

// A client that moves its request ring's write position where nothing was written (not on a record
// boundary) is dropped when the server reads it.
TEST(RequestRing, AClientThatBreaksItsWritePositionIsDropped) {
  SimServer server;
  RawShmClient hostile(server.api_port());
  ASSERT_NO_FATAL_FAILURE(join_with_request_ring(hostile));
  hostile.send_on_ring({{"op", "status"}, {"id", "s"}}, /*deferred=*/true);
  hostile.request_header()->head += 5;  // (before the server is woken: it reads only this)
  hostile.flush();
  EXPECT_TRUE(hostile.hung_up());
  ApiClient api(server.api_port());
  EXPECT_EQ(api.request({{"op", "status"}})["result"]["lockstep_clients"], 0);
}

}  // namespace
}  // namespace uavsim::client::testing
