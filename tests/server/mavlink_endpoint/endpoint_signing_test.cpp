// MAVLink 2 signing on the endpoint, as ArduPilot does it (GCS_Signing.cpp): SETUP_SIGNING sets the key
// for every link of the vehicle, outgoing MAVLink 2 frames are signed from then on, and incoming frames
// that are unsigned (except RADIO_STATUS) or wrongly signed are ignored and counted.
#include <chrono>

#include "test_gcs.hpp"

namespace uavsim::server::mavlink::testing {
namespace {

SecretKey key_of(std::uint8_t seed) {
  SecretKey k;
  for (std::size_t i = 0; i < k.size(); ++i) k[i] = static_cast<std::uint8_t>(seed + 7 * i);
  return k;
}

std::uint64_t wall_timestamp_10us() {
  const auto us = std::chrono::duration_cast<std::chrono::microseconds>(
      std::chrono::system_clock::now().time_since_epoch());
  return signing_timestamp_from_unix_us(static_cast<std::uint64_t>(us.count()));
}

class SigningTest : public EndpointTest {
 protected:
  // a client's SETUP_SIGNING; waits until frames signed with key arrive
  void setup_signing(TestGcs& g, const SecretKey& key, std::uint64_t initial_10us) {
    msg::SetupSigning s;
    s.target_system = 1;
    s.target_component = 1;
    s.initial_timestamp = initial_10us;
    s.secret_key = key;
    g.send(s);
    sync_client(g);
    step_for(0.01);  // the frame is handled at the next control step
  }

  // reads everything the vehicle queued so far (frames sent before signing started)
  void drain(TestGcs& g) {
    ASSERT_TRUE(server_->flush_queued());
    g.poll_once(20);
    g.poll_once(20);
  }

  // sends an arm COMMAND_LONG; true when it was acked within 1 s of sim time
  bool arm_acked(TestGcs& g) {
    msg::CommandLong c;
    c.command = cmd_id(MavCmd::ComponentArmDisarm);
    c.target_system = 1;
    c.target_component = 1;
    c.param1 = 1;
    const std::size_t acks = g.count<msg::CommandAck>();
    // the endpoint accounts for every frame it reads: accepted, or rejected for its signature; wait
    // for that before stepping, so a loaded machine cannot let the sim-time bound pass first
    auto accounted = [this] {
      const EndpointStats st = server_->stats(0);
      return st.frames_received + st.bad_signature + st.unsigned_rejected + st.replayed;
    };
    const std::uint64_t before = accounted();
    g.send(c);
    EXPECT_TRUE(wait_for([&] { return accounted() > before; })) << "the endpoint never read the frame";
    return step_until(g, [&] { return g.count<msg::CommandAck>() > acks; }, 1.0);
  }
};

TEST_F(SigningTest, SignedClientArmsUnsignedAndWronglySignedCommandsAreIgnored) {
  const SecretKey key = key_of(3);
  auto g = connect();
  wait_gps_ready(*g);
  EXPECT_EQ(command(*g, MavCmd::DoSetMode, {1, 4}), 0);  // GUIDED, before signing
  const std::uint64_t t0 = wall_timestamp_10us();
  setup_signing(*g, key, t0);
  drain(*g);

  // what the vehicle sends from now on carries valid signatures: a verifying parser drops nothing
  g->verify_with(key);
  g->clear();
  ASSERT_TRUE(step_until(*g, [&] { return g->count<msg::Heartbeat>() >= 2; }, 3.0));
  EXPECT_EQ(g->parser_stats().bad_signature, 0u);
  EXPECT_EQ(g->parser_stats().unsigned_rejected, 0u);
  EXPECT_EQ(g->parser_stats().replayed, 0u);
  std::uint64_t last_ts = 0;
  for (const Frame& f : g->frames()) {
    ASSERT_TRUE(f.signature) << "unsigned frame, msgid " << f.msgid;
    EXPECT_GT(f.signature->timestamp_10us, last_ts);  // strictly increasing
    EXPECT_GE(f.signature->timestamp_10us, t0);        // starts from SETUP_SIGNING's timestamp
    last_ts = f.signature->timestamp_10us;
  }

  // unsigned: ignored and counted
  EXPECT_FALSE(arm_acked(*g));
  EXPECT_FALSE(sim_->fc(0).armed());
  EXPECT_GE(server_->stats(0).unsigned_rejected, 1u);

  // signed with another key: ignored and counted
  g->sign_with(SigningParams{key_of(99), 0, wall_timestamp_10us()});
  EXPECT_FALSE(arm_acked(*g));
  EXPECT_FALSE(sim_->fc(0).armed());
  EXPECT_GE(server_->stats(0).bad_signature, 1u);

  // signed with the key: armed
  g->sign_with(SigningParams{key, 0, wall_timestamp_10us()});
  ASSERT_TRUE(arm_acked(*g));
  EXPECT_EQ(g->last<msg::CommandAck>()->result, 0);
  EXPECT_TRUE(sim_->fc(0).armed());
  EXPECT_EQ(server_->stats(0).replayed, 0u);
}

TEST_F(SigningTest, RadioStatusIsAcceptedUnsignedAndEachClientHasItsOwnLinkId) {
  const SecretKey key = key_of(5);
  auto a = connect();
  auto b = connect();
  setup_signing(*a, key, wall_timestamp_10us());
  const std::uint64_t handled = server_->stats(0).frames_handled;
  msg::RadioStatus r;
  r.rssi = 200;
  b->send(r);  // unsigned, from the other client
  sync_client(*b);
  step_for(0.01);
  EXPECT_GT(server_->stats(0).frames_handled, handled);
  EXPECT_EQ(server_->stats(0).unsigned_rejected, 0u);

  a->verify_with(key);
  b->verify_with(key);
  a->clear();
  b->clear();
  ASSERT_TRUE(step_until(*a, [&] { return a->count<msg::Heartbeat>() >= 1; }, 2.0));
  ASSERT_TRUE(step_until(*b, [&] { return b->count<msg::Heartbeat>() >= 1; }, 2.0));
  const Frame* fa = a->last_frame(msg::Heartbeat::kId);
  const Frame* fb = b->last_frame(msg::Heartbeat::kId);
  ASSERT_TRUE(fa->signature && fb->signature);
  EXPECT_NE(fa->signature->link_id, fb->signature->link_id);
}

TEST_F(SigningTest, AllZeroKeyDisablesSigning) {
  const SecretKey key = key_of(11);
  auto g = connect();
  setup_signing(*g, key, wall_timestamp_10us());
  g->sign_with(SigningParams{key, 0, wall_timestamp_10us()});
  setup_signing(*g, SecretKey{}, 0);  // signed, so it is accepted: turns signing off
  g->sign_with(std::nullopt);
  EXPECT_EQ(command(*g, kUnsupportedCmd),
            3);  // an unsigned command is answered again (UNSUPPORTED)
  g->clear();
  ASSERT_TRUE(step_until(*g, [&] { return g->count<msg::Heartbeat>() >= 1; }, 2.0));
  for (const Frame& f : g->frames()) EXPECT_FALSE(f.signature) << "msgid " << f.msgid;
  EXPECT_EQ(server_->stats(0).bad_signature, 0u);
}

class ConfiguredKeyTest : public EndpointTest {
 protected:
  void SetUp() override {
    sim_ = sim::testing::make_sim("empty.xml");
    EndpointConfig c;
    c.base_port = 0;
    c.signing_key = key_of(21);
    server_ = std::make_unique<MavlinkServer>(*sim_, c);
    server_->schedule(sim_->schedule());
  }
};

TEST_F(ConfiguredKeyTest, ServerStartedWithAKeySignsFromTheFirstFrame) {
  auto g = connect();
  g->verify_with(key_of(21));
  ASSERT_TRUE(step_until(*g, [&] { return g->count<msg::Heartbeat>() >= 2; }, 2.0));
  EXPECT_EQ(g->parser_stats().unsigned_rejected, 0u);
  EXPECT_EQ(g->parser_stats().bad_signature, 0u);
  EXPECT_EQ(g->parser_stats().replayed, 0u);
  EXPECT_EQ(command(*g, kUnsupportedCmd), -1);  // unsigned: no answer
  EXPECT_GE(server_->stats(0).unsigned_rejected, 1u);
  g->sign_with(SigningParams{key_of(21), 0, wall_timestamp_10us()});
  EXPECT_EQ(command(*g, kUnsupportedCmd), 3);
}

}  // namespace
}  // namespace uavsim::server::mavlink::testing
