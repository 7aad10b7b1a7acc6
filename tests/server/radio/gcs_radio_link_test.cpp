// The GCS link relay over ns-3's 802.11 (radio/gcs_radio_link.hpp): real UDP sockets on loopback
// stand for the UAV's and the ground station's programs, the relay set is pumped by a simulation
// of tests/data/worlds/radio_wall.xml (uav0 at the origin, a wall at x = 20 m of geom group 3,
// 40 dB), and every datagram crosses the channel between uav0's node and a ground node.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "../../support/loopback_udp.hpp"
#include "physics/object_bodies.hpp"
#include "radio/gcs_relay.hpp"
#include "sim/simulation.hpp"

namespace uavsim::server::radio {
namespace {

// 500 Hz control: the relay pumps every 2 ms
constexpr double kControl_s = 0.002;
// a datagram enters the channel within one control step of its send (send spread), then takes
// DIFS (34 us) + at most 15 backoff slots (135 us) + a 1500-byte frame's airtime at 6 Mbit/s
// (about 2.05 ms) + SIFS and the ACK (about 60 us) before it is received, and is sent on at the
// next pump: at most 2 steps + 2.3 ms, and never before one step (the channel's floor); the 1 ms
// physics step between a send and the sim time read after it widens both ends by a step
constexpr double kMinLatency_s = kControl_s;
constexpr double kMaxLatency_s = 2 * kControl_s + 0.0023 + 0.001;
constexpr double kStepTol_s = 1e-12;

int udp_socket(uint16_t* port) { return uavsim::testing::bind_loopback_udp(port, SOCK_NONBLOCK); }

void send_to(int fd, uint16_t port, const std::vector<uint8_t>& bytes) {
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  a.sin_port = htons(port);
  sendto(fd, bytes.data(), bytes.size(), 0, reinterpret_cast<sockaddr*>(&a), sizeof(a));
}

std::vector<std::vector<uint8_t>> receive_all(int fd) {
  std::vector<std::vector<uint8_t>> out;
  std::vector<uint8_t> buf(65536);
  for (;;) {
    const ssize_t n = recv(fd, buf.data(), buf.size(), MSG_DONTWAIT);
    if (n < 0) return out;
    out.emplace_back(buf.begin(), buf.begin() + n);
  }
}

// a datagram of n bytes that starts with its index
std::vector<uint8_t> datagram(uint32_t index, size_t n = 64) {
  std::vector<uint8_t> d(n, 0x5A);
  std::memcpy(d.data(), &index, sizeof(index));
  return d;
}

uint32_t index_of(const std::vector<uint8_t>& d) {
  uint32_t i = 0;
  std::memcpy(&i, d.data(), sizeof(i));
  return i;
}

// what one run saw: each datagram's index and arrival (sim time), the relay's counters
struct Seen {
  std::vector<std::pair<uint32_t, double>> up, down;
  RelayStats stats;
};

class GcsRadioLinkTest : public ::testing::Test {
 protected:
  // the world, the relay set over the radio with the ground node at gcs, vehicle 0's relay open
  // (a second start begins afresh: a new world, relay set and helper)
  void start(const Eigen::Vector3d& gcs, double shadowing_sigma_db, bool world_obstacles) {
    TearDown();
    failures_.clear();
    latencies_.clear();
    physics::ComposeOptions o;
    o.models_dir = UAVSIM_MODELS_DIR;
    sim_ = std::make_unique<sim::Simulation>(
        physics::World::load(std::string(UAVSIM_TEST_DATA_DIR) + "/worlds/radio_wall.xml", o),
        sim::SimConfig{});
    ASSERT_NEAR(sim_->control_dt_s(), kControl_s, kStepTol_s);
    GcsRadioOptions radio;
    radio.ns3.helper_path = UAVSIM_NS3_HELPER_PATH;
    radio.gcs_position_enu_m = gcs;
    radio.config.shadowing_sigma_db = shadowing_sigma_db;
    bool use_ns3 = true;
    if (world_obstacles) apply_world_gcs_settings(sim_->world(), true, &use_ns3, &radio);
    relays_ = &GcsRelaySet::attach(*sim_, "127.0.0.1");
    relays_->use_radio(std::make_unique<GcsRadioLink>(*sim_, radio));
    relays_->set_on_failure([this](const std::string& why) { failures_.push_back(why); });
    uav_fd_ = udp_socket(&uav_port_);
    gcs_fd_ = udp_socket(&gcs_port_);
    std::string error;
    relay_ = relays_->open(0, 0, 0, std::string("127.0.0.1"), gcs_port_, &error);
    ASSERT_NE(relay_, nullptr) << error;
  }

  void TearDown() override {
    if (uav_fd_ >= 0) close(uav_fd_);
    if (gcs_fd_ >= 0) close(gcs_fd_);
    uav_fd_ = gcs_fd_ = -1;
  }

  // count datagrams each way, one up and one down every 20 ms, then 0.1 s more for the last ones;
  // what arrived is recorded in *seen, the relay's counters (since its start) too
  void exchange(uint32_t count, Seen* seen, size_t bytes = 64) {
    std::vector<double> sent_up(count), sent_down(count);
    const int steps = static_cast<int>(count) * 20 + 100;
    for (int k = 0; k < steps; ++k) {
      const uint32_t i = static_cast<uint32_t>(k / 20);
      if (k % 20 == 0 && i < count) {
        sent_up[i] = sim_->time_s();
        send_to(uav_fd_, relay_->uav_port(), datagram(i, bytes));
      }
      // downlink once the relay has learned the UAV's address from its first datagram
      if (k % 20 == 10 && i < count) {
        sent_down[i] = sim_->time_s();
        send_to(gcs_fd_, relay_->gcs_port(), datagram(i, bytes));
      }
      sim_->step();
      for (const auto& d : receive_all(gcs_fd_)) {
        seen->up.emplace_back(index_of(d), sim_->time_s());
        latencies_.push_back(sim_->time_s() - sent_up[index_of(d)]);
        ASSERT_EQ(d, datagram(index_of(d), bytes));
      }
      for (const auto& d : receive_all(uav_fd_)) {
        seen->down.emplace_back(index_of(d), sim_->time_s());
        latencies_.push_back(sim_->time_s() - sent_down[index_of(d)]);
        ASSERT_EQ(d, datagram(index_of(d), bytes));
      }
    }
    seen->stats = relay_->stats();
  }

  // teleports uav0 to p and holds it there
  void place_uav0(const Eigen::Vector3d& p) {
    const double pos[3] = {p.x(), p.y(), p.z()};
    const double quat[4] = {1, 0, 0, 0};
    sim_->world().set_pose(0, pos, quat);
    sim_->world().park(0);
  }

  std::unique_ptr<sim::Simulation> sim_;
  GcsRelaySet* relays_ = nullptr;
  GcsRelay* relay_ = nullptr;
  int uav_fd_ = -1, gcs_fd_ = -1;
  uint16_t uav_port_ = 0, gcs_port_ = 0;
  std::vector<std::string> failures_;
  std::vector<double> latencies_;
};

TEST_F(GcsRadioLinkTest, DatagramsCrossBothWaysWithAn80211Latency) {
  // 10 m away, in the open: 20 dBm - 65 dB = -45 dBm, 37 dB above the sensitivity
  start(Eigen::Vector3d(0.0, 10.0, 1.5), 4.0, true);
  EXPECT_STREQ(relays_->backend_name(), "ns3");
  Seen seen;
  exchange(20, &seen);
  EXPECT_EQ(seen.up.size(), 20u);
  EXPECT_EQ(seen.down.size(), 20u);
  EXPECT_EQ(seen.stats.to_gcs_forwarded, 20u);
  EXPECT_EQ(seen.stats.to_uav_forwarded, 20u);
  EXPECT_EQ(seen.stats.to_gcs_dropped + seen.stats.to_uav_dropped, 0u);
  ASSERT_EQ(latencies_.size(), 40u);
  for (double l : latencies_) {
    EXPECT_GE(l, kMinLatency_s);
    EXPECT_LE(l, kMaxLatency_s);
  }
  EXPECT_TRUE(failures_.empty());
}

TEST_F(GcsRadioLinkTest, TheFaultApisImpairmentAppliesFirst) {
  start(Eigen::Vector3d(0.0, 10.0, 1.5), 0.0, false);
  // 50 ms of latency on the relay's side, then the radio's few ms
  relay_->impair(0.0, 0.05, 0.0, sim_->time_s());
  Seen delayed;
  exchange(5, &delayed);
  EXPECT_EQ(delayed.up.size(), 5u);
  EXPECT_EQ(delayed.down.size(), 5u);
  for (double l : latencies_) {
    EXPECT_GE(l, 0.05 + kMinLatency_s);
    EXPECT_LE(l, 0.05 + kMaxLatency_s);
  }
  // an outage drops everything at the relay, before the radio
  relay_->impair(0.0, 0.0, 10.0, sim_->time_s());
  Seen cut;
  exchange(5, &cut);
  EXPECT_TRUE(cut.up.empty());
  EXPECT_TRUE(cut.down.empty());
  EXPECT_EQ(cut.stats.to_gcs_dropped, 5u);
  EXPECT_EQ(cut.stats.to_uav_dropped, 5u);
  EXPECT_EQ(relays_->radio()->channel().link(0, 2).sent, 5u);  // uav0 -> ground node: the first 5
}

TEST_F(GcsRadioLinkTest, AResetStartsTheRadioAndTheCountersAfresh) {
  start(Eigen::Vector3d(0.0, 10.0, 1.5), 0.0, false);
  Seen before, after;
  exchange(3, &before);
  EXPECT_EQ(before.stats.to_gcs_forwarded, 3u);
  sim_->reset(1);
  EXPECT_EQ(relay_->stats().to_gcs_forwarded, 0u);
  exchange(3, &after);
  EXPECT_EQ(after.up.size(), 3u);
  EXPECT_EQ(after.down.size(), 3u);
  EXPECT_EQ(after.stats.to_gcs_forwarded, 3u);
  EXPECT_EQ(after.stats.to_uav_forwarded, 3u);
  EXPECT_TRUE(failures_.empty());
}

TEST_F(GcsRadioLinkTest, DatagramsOverTheLargestFrameAreDroppedAndCounted) {
  start(Eigen::Vector3d(0.0, 10.0, 1.5), 0.0, false);
  ASSERT_EQ(relays_->radio()->max_datagram_bytes(), 1500u);
  Seen full, over;
  exchange(3, &full, 1500);
  EXPECT_EQ(full.up.size(), 3u);
  EXPECT_EQ(full.down.size(), 3u);
  exchange(3, &over, 1501);
  EXPECT_TRUE(over.up.empty());
  EXPECT_TRUE(over.down.empty());
  EXPECT_EQ(over.stats.to_gcs_dropped, 3u);
  EXPECT_EQ(over.stats.to_uav_dropped, 3u);
  EXPECT_EQ(over.stats.to_gcs_forwarded, 3u);
}

TEST_F(GcsRadioLinkTest, AVehicleFlownOutOfRangeLosesTheLinkAndRegainsIt) {
  // without shadowing the range is 10^((20 + 82 - 40.05) / 25) = 301 m
  start(Eigen::Vector3d(0.0, 10.0, 1.5), 0.0, false);
  Seen near, far, back;
  exchange(5, &near);
  EXPECT_EQ(near.up.size(), 5u);
  // 1 km away: 20 - 40.05 - 25 log10(1000) = -95 dBm, 13 dB below the sensitivity
  place_uav0(Eigen::Vector3d(0.0, -1000.0, 20.0));
  exchange(5, &far);
  EXPECT_TRUE(far.up.empty());
  EXPECT_TRUE(far.down.empty());
  EXPECT_EQ(far.stats.to_gcs_dropped, 5u);
  EXPECT_EQ(far.stats.to_uav_dropped, 5u);
  place_uav0(Eigen::Vector3d(0.0, 0.0, 2.0));
  exchange(5, &back);
  EXPECT_EQ(back.up.size(), 5u);
  EXPECT_EQ(back.down.size(), 5u);
  EXPECT_EQ(back.stats.to_gcs_forwarded, 10u);
  EXPECT_EQ(back.stats.to_uav_forwarded, 10u);
}

TEST_F(GcsRadioLinkTest, AWallBetweenVehicleAndGcsDropsTheLinkAsItDropsA2aLinks) {
  // the ground station beyond the wall, 40.3 m from uav0: -60 dBm in the open, -100 dBm through
  // the wall's 40 dB (the world's uavsim:radio_obstacle_loss_db)
  start(Eigen::Vector3d(40.0, 5.0, 1.5), 0.0, true);
  Seen blocked, clear;
  exchange(5, &blocked);
  EXPECT_TRUE(blocked.up.empty());
  EXPECT_TRUE(blocked.down.empty());
  EXPECT_EQ(blocked.stats.to_gcs_dropped, 5u);
  EXPECT_EQ(blocked.stats.to_uav_dropped, 5u);
  // the wall 30 m aside: the path is clear again (the cached cast is at most 0.1 s old)
  ASSERT_TRUE(physics::set_mocap_pose(sim_->world(), sim_->world().body_id("wall"),
                                      Eigen::Vector3d(20.0, 30.0, 5.0),
                                      Eigen::Quaterniond::Identity()));
  for (int k = 0; k < 150; ++k) sim_->step();
  exchange(5, &clear);
  EXPECT_EQ(clear.up.size(), 5u);
  EXPECT_EQ(clear.down.size(), 5u);
}

TEST_F(GcsRadioLinkTest, TheSameSeedGivesTheSameArrivalsAndCounters) {
  // beyond the edge of the range (360 m: 20 - 40.05 - 25 log10(360) = -84 dBm against -82, with
  // 4 dB of shadowing drawn per transmission): retries, and some datagrams lost after all of them
  Seen seen[2];
  for (Seen& s : seen) {
    start(Eigen::Vector3d(0.0, 360.0, 1.5), 4.0, false);
    exchange(40, &s);
  }
  EXPECT_GT(seen[0].up.size() + seen[0].down.size(), 0u);
  EXPECT_GT(seen[0].stats.to_gcs_dropped + seen[0].stats.to_uav_dropped, 0u);
  // every datagram is accounted for: forwarded or dropped
  EXPECT_EQ(seen[0].stats.to_gcs_forwarded + seen[0].stats.to_gcs_dropped, 40u);
  EXPECT_EQ(seen[0].stats.to_uav_forwarded + seen[0].stats.to_uav_dropped, 40u);
  EXPECT_EQ(seen[0].up, seen[1].up);
  EXPECT_EQ(seen[0].down, seen[1].down);
  EXPECT_EQ(seen[0].stats.to_gcs_forwarded, seen[1].stats.to_gcs_forwarded);
  EXPECT_EQ(seen[0].stats.to_gcs_dropped, seen[1].stats.to_gcs_dropped);
  EXPECT_EQ(seen[0].stats.to_uav_forwarded, seen[1].stats.to_uav_forwarded);
  EXPECT_EQ(seen[0].stats.to_uav_dropped, seen[1].stats.to_uav_dropped);
}

TEST_F(GcsRadioLinkTest, AHelperThatDiesIsReportedOnceAndNothingMorePasses) {
  start(Eigen::Vector3d(0.0, 10.0, 1.5), 0.0, false);
  Seen before, after;
  exchange(2, &before);
  ASSERT_EQ(before.up.size(), 2u);
  auto* ns3 = dynamic_cast<Ns3Channel*>(&relays_->radio()->channel());
  ASSERT_NE(ns3, nullptr);
  ASSERT_EQ(::kill(ns3->helper_pid(), SIGKILL), 0);
  exchange(3, &after);
  ASSERT_EQ(failures_.size(), 1u);
  EXPECT_NE(failures_[0].find("signal 9"), std::string::npos) << failures_[0];
  EXPECT_TRUE(after.up.empty());
  EXPECT_EQ(after.stats.to_gcs_forwarded, 2u);
  EXPECT_GE(after.stats.to_gcs_dropped, 2u);  // refused once the failure is known
}

}  // namespace
}  // namespace uavsim::server::radio
