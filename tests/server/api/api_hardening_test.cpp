// Hostile and careless API input: deep nesting, structured ids, wrong field types, numbers out of
// range, replies in request order, a half-closed request, and the connection / reply-queue limits.
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <string>

#include "../../support/fd_exhaustion.hpp"
#include "api/api_server.hpp"
#include "api/line_server.hpp"
#include "api/request_fields.hpp"
#include "api_fixture.hpp"

namespace uavsim::server::api {
namespace {

using testing::error_code;
using testing::Json;
using testing::paused;
using testing::RawClient;
using testing::TestServer;

std::string nested(size_t depth) { return std::string(depth, '[') + std::string(depth, ']'); }

TEST(ApiHardening, DeeplyNestedRequestsAreRefusedAndTheServerStaysUp) {
  TestServer server("empty.xml", paused());
  RawClient c(server.port());
  // a 140 KB id nested 70k deep once overflowed the stack when it was echoed
  c.send_raw("{\"op\":\"status\",\"id\":" + nested(70000) + "}\n");
  Json r = c.reply();
  EXPECT_EQ(error_code(r), "bad_request") << r;
  EXPECT_TRUE(r["id"].is_null());
  // the same depth anywhere in a request, for a good op and a bad one
  c.send_raw("{\"op\":\"status\",\"x\":" + nested(70000) + "}\n");
  EXPECT_EQ(error_code(c.reply()), "bad_request");
  c.send_raw("{\"op\":\"no_such_op\",\"x\":" + nested(70000) + "}\n");
  EXPECT_EQ(error_code(c.reply()), "bad_request");
  // at the limit a request is fine
  c.send_raw("{\"op\":\"status\",\"id\":7,\"x\":" + nested(kMaxNestingDepth) + "}\n");
  r = c.reply();
  EXPECT_TRUE(r["ok"]) << r;
  EXPECT_EQ(r["id"], 7);
}

TEST(ApiHardening, OnlyScalarIdsAreEchoed) {
  TestServer server("empty.xml", paused());
  RawClient c(server.port());
  Json r = c.request({{"op", "status"}, {"id", {{"a", 1}}}});
  EXPECT_EQ(error_code(r), "bad_field");
  EXPECT_TRUE(r["id"].is_null());
  EXPECT_EQ(error_code(c.request({{"op", "status"}, {"id", Json::array({1, 2})}})), "bad_field");
  for (const Json& id : {Json(3), Json("x"), Json(true), Json(nullptr), Json(2.5)}) {
    r = c.request({{"op", "status"}, {"id", id}});
    EXPECT_TRUE(r["ok"]) << r;
    EXPECT_EQ(r["id"], id);
  }
}

TEST(ApiHardening, RepliesComeBackInRequestOrder) {
  TestServer server("empty.xml", paused());
  RawClient c(server.port());
  // good, unknown op, bad JSON, good, no op, good: errors made on the I/O thread once overtook the
  // requests queued for the loop
  for (int trial = 0; trial < 20; ++trial) {
    c.send_raw("{\"op\":\"status\",\"id\":1}\n{\"op\":\"nope\",\"id\":2}\n{bad\n{\"op\":\"status\",\"id\":4}\n"
               "{\"id\":5}\n{\"op\":\"vehicles\",\"id\":6}\n");
    std::vector<Json> ids;
    for (int k = 0; k < 6; ++k) ids.push_back(c.reply()["id"]);
    EXPECT_EQ(Json(ids), Json::parse("[1, 2, null, 4, 5, 6]")) << "trial " << trial;
  }
}

TEST(ApiHardening, FieldsOfTheWrongTypeAreBadField) {
  TestServer server("empty.xml", paused());
  RawClient c(server.port());
  EXPECT_EQ(error_code(c.request({{"op", "step"}, {"steps", "x"}})), "bad_field");
  EXPECT_EQ(error_code(c.request({{"op", "set_rate"}, {"rate", "fast"}})), "bad_field");
  EXPECT_EQ(error_code(c.request({{"op", "reset"}, {"seed", "1"}})), "bad_field");
  EXPECT_EQ(error_code(c.request({{"op", "gimbal"}, {"gimbal", 3}})), "bad_field");
  EXPECT_EQ(error_code(c.request({{"op", "kill_vehicle"}, {"vehicle", 0}, {"reason", 5}})), "bad_field");
  EXPECT_EQ(error_code(c.request({{"op", "gps_denied"}, {"vehicle", 0}, {"denied", "yes"}})), "bad_field");
  EXPECT_EQ(error_code(c.request({{"op", "lockstep_join"}, {"period_s", Json::array({1})}})), "bad_field");
  // the message names the field
  const Json r = c.request({{"op", "step"}, {"steps", "x"}});
  EXPECT_NE(r["error"]["message"].get<std::string>().find("steps"), std::string::npos) << r;
  // nothing was applied: still at time 0, still alive
  EXPECT_EQ(c.request({{"op", "status"}})["result"]["time_s"], 0.0);
  EXPECT_EQ(c.request({{"op", "vehicles"}})["result"]["vehicles"][0]["crashed"], false);
}

TEST(ApiHardening, NumbersOutOfRangeAreBadField) {
  TestServer server("empty.xml", paused());
  RawClient c(server.port());
  // seeds: a double out of uint64 range once became 0; an exact uint64 is kept
  EXPECT_EQ(error_code(c.request({{"op", "reset"}, {"seed", 1e30}})), "bad_field");
  EXPECT_EQ(error_code(c.request({{"op", "reset"}, {"seed", 18446744073709551616.0}})), "bad_field");
  EXPECT_EQ(error_code(c.request({{"op", "reset"}, {"seed", -1}})), "bad_field");
  Json r = c.request({{"op", "reset"}, {"seed", 18446744073709551615ull}});
  ASSERT_TRUE(r["ok"]) << r;
  EXPECT_EQ(r["result"]["seed"].get<uint64_t>(), 18446744073709551615ull);
  // a lockstep timeout of 1e10 s once overflowed the deadline and counted as expired
  EXPECT_EQ(error_code(c.request({{"op", "lockstep_join"}, {"period_s", 0.1}, {"timeout_s", 1e10}})),
            "bad_field");
  EXPECT_EQ(error_code(c.request({{"op", "set_rate"}, {"rate", 1e-300}})), "bad_field");
  EXPECT_EQ(error_code(c.request({{"op", "events"}, {"from_seq", 1e30}})), "bad_field");
  EXPECT_EQ(error_code(c.request({{"op", "gps_glitch"}, {"vehicle", 0}, {"offset_enu_m", {1e300, 0, 0}}})),
            "bad_field");
  EXPECT_EQ(error_code(c.request({{"op", "step"}, {"steps", 1e300}})), "bad_field");
  EXPECT_TRUE(c.request({{"op", "set_rate"}, {"rate", 0}})["ok"]);
}

TEST(ApiHardening, ARequestFollowedByShutdownOfTheSendingSideGetsItsReply) {
  TestServer server("empty.xml", paused());
  RawClient c(server.port());
  // the last line even without its newline
  c.send_raw("{\"op\":\"status\",\"id\":1}\n{\"op\":\"status\",\"id\":2}");
  ASSERT_EQ(c.shutdown_sending(), 0);
  EXPECT_EQ(c.reply()["id"], 1);
  EXPECT_EQ(c.reply()["id"], 2);
  EXPECT_TRUE(c.at_eof());  // and then the server closes
}

TEST(ApiHardening, ConnectionsOverTheLimitAreToldWhyAndClosed) {
  ApiConfig config = paused();
  config.max_connections = 2;
  TestServer server("empty.xml", config);
  RawClient a(server.port()), b(server.port());
  ASSERT_TRUE(a.request({{"op", "status"}})["ok"]);
  ASSERT_TRUE(b.request({{"op", "status"}})["ok"]);
  RawClient third(server.port());  // its first message is the error instead of the hello
  EXPECT_EQ(error_code(third.hello()), "overloaded") << third.hello();
  EXPECT_TRUE(third.at_eof());
  EXPECT_TRUE(a.request({{"op", "status"}})["ok"]);
}

TEST(ApiHardening, AReplyPastTheQueueCapEndsTheConnectionWithOverloaded) {
  ApiConfig config = paused();
  config.max_pending_bytes = 4096;  // more than the hello, less than a "vehicles" reply for 100 vehicles
  TestServer server("grid100.xml", config);
  RawClient c(server.port());
  EXPECT_EQ(error_code(c.request({{"op", "vehicles"}})), "overloaded");
  EXPECT_TRUE(c.at_eof());
  RawClient next(server.port());
  EXPECT_TRUE(next.request({{"op", "status"}})["ok"]);
}

// A connection that arrives while the process has no descriptor left would keep the listener readable and
// the I/O thread spinning; it is accepted on the spare descriptor and closed at once (the peer reads the
// end of the stream), and connections are accepted as before once descriptors are free.
TEST(ApiHardening, AConnectionWithNoDescriptorLeftIsClosedNotSpunOn) {
  std::atomic<int> connects{0};
  LineServer::Callbacks callbacks;
  callbacks.on_connect = [&](uint64_t) { connects.fetch_add(1); };
  LineServer server("127.0.0.1", 0, LineServer::Limits{}, callbacks);
  server.start();
  sockaddr_in sa{};
  sa.sin_family = AF_INET;
  sa.sin_port = htons(server.port());
  sa.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  // waits (wall clock, bounded) for a condition the I/O thread makes true
  auto wait_for = [](auto done) {
    const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(5);
    while (!done() && std::chrono::steady_clock::now() < end) poll(nullptr, 0, 1);
    return done();
  };
  // the I/O thread is running (a first connection accepted) before the process runs out: under
  // UBSan the vptr check of a thread's first call probes memory through a pipe, which needs descriptors
  const int first = socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  ASSERT_EQ(connect(first, reinterpret_cast<sockaddr*>(&sa), sizeof(sa)), 0);
  ASSERT_TRUE(wait_for([&] { return connects.load() == 1; }));
  close(first);
  // the client's socket exists before the process runs out
  const int client = socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  ASSERT_GE(client, 0);
  {
    uavsim::testing::FdExhaustion no_fds;
    ASSERT_TRUE(no_fds.exhausted());
    // the handshake completes in the listen backlog, without the server accepting
    ASSERT_EQ(connect(client, reinterpret_cast<sockaddr*>(&sa), sizeof(sa)), 0);
    EXPECT_TRUE(wait_for([&] { return server.fd_exhausted_accepts() >= 1; }));
    pollfd p{client, POLLIN, 0};
    ASSERT_EQ(poll(&p, 1, 5000), 1) << "the waiting connection was never closed";
    char byte = 0;
    EXPECT_LE(recv(client, &byte, 1, 0), 0);
  }
  close(client);
  EXPECT_EQ(connects.load(), 1);
  EXPECT_EQ(server.fd_exhausted_accepts(), 1u);

  // descriptors are back: the next connection is accepted
  const int next = socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  ASSERT_EQ(connect(next, reinterpret_cast<sockaddr*>(&sa), sizeof(sa)), 0);
  EXPECT_TRUE(wait_for([&] { return connects.load() == 2; }));
  close(next);
  server.stop();
}

}  // namespace
}  // namespace uavsim::server::api
