// Bad input is skipped and counted; the vehicle and the other clients are unaffected.
#include <random>

#include "test_gcs.hpp"

namespace uavsim::server::mavlink::testing {
namespace {

constexpr double kSimTimeTolS = 0.01;

class BadInputTest : public EndpointTest {
 protected:
  int unknown_command(TestGcs& g) { return command(g, kUnsupportedCmd); }
  void send_garbage_then_expect_ack(TestGcs& g, std::span<const std::uint8_t> bytes) {
    const auto before = server_->stats(0).bytes_received;
    g.send_raw(bytes);
    ASSERT_TRUE(wait_for([&] { return server_->stats(0).bytes_received >= before + bytes.size(); }));
    EXPECT_EQ(unknown_command(g), 3) << "vehicle stopped answering after bad input";
  }
};

TEST_F(BadInputTest, RandomBytesAreSkipped) {
  auto g = connect();
  std::mt19937 rng(7);
  std::vector<std::uint8_t> junk(20000);
  for (auto& b : junk) b = static_cast<std::uint8_t>(rng());
  send_garbage_then_expect_ack(*g, junk);
  EXPECT_GT(server_->stats(0).bytes_discarded, 10000u);
}

TEST_F(BadInputTest, BadCrcIsCounted) {
  auto g = connect();
  msg::CommandLong c;
  c.command = cmd_id(MavCmd::ComponentArmDisarm);
  c.param1 = 1;
  c.target_system = 1;
  EncodedFrame f = encode(FrameHeader{255, 190, 0, Version::kV2, std::nullopt}, c);
  f.bytes[f.size - 1] ^= 0x55;
  send_garbage_then_expect_ack(*g, f.view());
  EXPECT_GE(server_->stats(0).bad_crc, 1u);
  EXPECT_FALSE(sim_->fc(0).armed());
}

TEST_F(BadInputTest, TruncatedFrameFollowedByAGoodOneIsRecovered) {
  auto g = connect();
  msg::CommandLong c;
  c.command = cmd_id(MavCmd::ComponentArmDisarm);
  c.param1 = 1;
  c.target_system = 1;
  const EncodedFrame f = encode(FrameHeader{255, 190, 0, Version::kV2, std::nullopt}, c);
  send_garbage_then_expect_ack(*g, f.view().first(f.size / 2));
  EXPECT_FALSE(sim_->fc(0).armed());
}

TEST_F(BadInputTest, UnknownMessageIdAndBogusLengthAreCounted) {
  auto g = connect();
  // v2 header with msgid 0xABCDEF (not in the dialect) and a 20-byte payload
  std::vector<std::uint8_t> unknown = {0xFD, 20, 0, 0, 0, 255, 190, 0xEF, 0xCD, 0xAB};
  unknown.resize(unknown.size() + 20 + 2, 0x11);
  // v1 HEARTBEAT header claiming 200 payload bytes (HEARTBEAT has 9)
  std::vector<std::uint8_t> bogus = {0xFE, 200, 0, 255, 190, 0};
  bogus.resize(bogus.size() + 202, 0x22);
  std::vector<std::uint8_t> both = unknown;
  both.insert(both.end(), bogus.begin(), bogus.end());
  send_garbage_then_expect_ack(*g, both);
  const EndpointStats s = server_->stats(0);
  EXPECT_GE(s.unknown_msgid + s.bad_length + s.bad_crc, 2u);
}

TEST_F(BadInputTest, ValidButUnhandledMessagesAreCounted) {
  auto g = connect();
  msg::Ping p;  // in the dialect, not acted on
  g->send(p);
  sync_client(*g);
  step_for(0.01);
  EXPECT_EQ(server_->stats(0).unhandled_messages, 1u);
  EXPECT_EQ(unknown_command(*g), 3);
}

TEST_F(BadInputTest, NanSetpointIsRejectedAndTheVehicleHolds) {
  auto g = connect();
  msg::SetPositionTargetLocalNed sp;
  sp.target_system = 1;
  sp.coordinate_frame = 1;
  sp.type_mask = 3527;
  sp.vx = std::numeric_limits<float>::quiet_NaN();
  g->send(sp);
  sync_client(*g);
  step_for(0.01);
  EXPECT_EQ(server_->stats(0).rejected_inputs, 1u);
}

TEST_F(BadInputTest, ClientThatNeverReadsIsCappedAndCostsNobodyElse) {
  // a small buffer so the cap is reached quickly
  server_.reset();
  EndpointConfig c;
  c.base_port = 0;
  c.client_buffer_bytes = 64 * 1024;
  server_ = std::make_unique<MavlinkServer>(*sim_, c);
  server_->schedule(sim_->schedule());
  clients_.clear();
  auto lazy = connect(0, Version::kV2, 4096);  // never reads, tiny socket buffer
  auto good = connect();
  // make lots of telemetry: every message at 500 Hz for both
  for (TestGcs* g : {lazy.get(), good.get()}) {
    for (std::uint32_t id : {0u, 1u, 24u, 30u, 31u, 32u, 33u, 74u, 147u}) {
      msg::CommandLong cmd;
      cmd.command = cmd_id(MavCmd::SetMessageInterval);
      cmd.target_system = 1;
      cmd.param1 = static_cast<float>(id);
      cmd.param2 = 1000;
      g->send(cmd);
    }
  }
  sync_client(*good);
  const double wall_start = sim_->time_s();
  std::size_t good_hb = 0;
  // 20 s of sim time: the lazy client's socket and buffer fill up; the good client keeps receiving.
  // Every 10 steps (~4 KB of its telemetry) the I/O thread is let catch up (flush_queued does not
  // wait for a client whose socket is full: the lazy one) and the good client reads, so its own
  // buffer never fills however busy the machine is: what it loses would be the lazy client's doing.
  int steps = 0;
  while (sim_->time_s() < wall_start + 20.0) {
    sim_->step();
    if (++steps % 10 == 0) {
      ASSERT_TRUE(server_->flush_queued());
      good->poll_once(0);
    }
  }
  ASSERT_TRUE(server_->flush_queued());
  // 500 Hz x 20 s = 10000 heartbeats, every one delivered
  ASSERT_TRUE(wait_for([&] {
    good->poll_once(5);
    good_hb = good->count<msg::Heartbeat>();
    return good_hb >= 9999;
  }, 10.0)) << good_hb;
  const EndpointStats s = server_->stats(0);
  EXPECT_GT(s.frames_dropped_full, 0u);
  EXPECT_NEAR(sim_->time_s(), wall_start + 20.0, kSimTimeTolS);
  EXPECT_EQ(unknown_command(*good), 3);
}

TEST_F(BadInputTest, HundredClientsConnectingAndDroppingAreCleanedUp) {
  for (int round = 0; round < 100; ++round) {
    TestGcs g(server_->port(0));
    ASSERT_TRUE(g.connected());
    if (round % 2 == 0) {
      msg::Heartbeat hb;
      hb.type = 6;
      g.send(hb);
    }
    step_for(0.002);
  }
  ASSERT_TRUE(wait_for([&] { return server_->stats(0).clients_closed == 100; }));
  EXPECT_EQ(server_->stats(0).clients_accepted, 100u);
  EXPECT_EQ(server_->client_count(0), 0u);
  // all closed, so nothing more of theirs arrives; a heartbeat may be lost to a reset, so count what came
  frames_from_unlisted_clients_ = server_->stats(0).frames_received;
  step_for(0.1);  // the loop thread forgets them without trouble
  auto g = connect();
  EXPECT_EQ(unknown_command(*g), 3);
}

}  // namespace
}  // namespace uavsim::server::mavlink::testing
