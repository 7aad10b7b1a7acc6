// client_cpp over MAVLink UDP, both ways ArduPilot SITL and mavlink-router offer it: the vehicle listens
// (server udpin:, client udp:) and the vehicle sends to a listening ground station (server udp:, client
// udpin:). Under lockstep, each flight takes off, flies to a point and is checked against ground truth.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include "../support/loopback_udp.hpp"
#include "sim_harness.hpp"
#include "uavsim/client/event_loop.hpp"
#include "uavsim/client/vehicle.hpp"

namespace uavsim::client::testing {
namespace {

constexpr double kPositionTolM = 0.6;

// a UDP port free now (the kernel's pick for a socket bound to port 0, released again)
int free_udp_port() {
  std::uint16_t port = 0;
  ::close(uavsim::testing::bind_loopback_udp(&port));
  return port;
}

// take off to 6 m, fly 8 m east, and land-free check against the truth; over the given link address
void fly_over(SimServer& server, const std::string& address) {
  auto l = EventLoop::create(LoopConfig::lockstep("127.0.0.1", server.api_port(), 0.02));
  ASSERT_TRUE(l) << l.message();
  std::unique_ptr<EventLoop> loop = std::move(*l);
  ApiClient api(server.api_port());
  ASSERT_EQ(api.request({{"op", "resume"}}).value("ok", false), true);
  Vehicle uav(*loop);
  auto r = uav.connect(address, 10);
  ASSERT_TRUE(r) << address << ": " << r.message();
  ASSERT_TRUE(r = uav.wait_ready(60)) << r.message();
  ASSERT_TRUE(r = uav.set_mode(FlightMode::kGuided)) << r.message();
  ASSERT_TRUE(r = uav.arm()) << r.message();
  ASSERT_TRUE(r = uav.takeoff(6.0)) << r.message();
  const Eigen::Vector3d target(8.0, 0.0, 6.0);
  ASSERT_TRUE(r = uav.goto_local_enu(target)) << r.message();
  ASSERT_TRUE(r = uav.wait_position_enu(target, 0.5, 30)) << r.message();
  EXPECT_LT((api.truth_position_enu() - target).norm(), kPositionTolM);
  EXPECT_LT((uav.telemetry().position_enu_m - target).norm(), kPositionTolM);
  // the commands came over UDP: the TCP endpoint had no client
  EXPECT_EQ(server.mavlink_stats().clients_accepted, 1u);
  EXPECT_GT(server.mavlink_stats().commands, 2u);
}

TEST(ClientUdp, FliesAVehicleThatListensOnUdpin) {
  SimServer server("empty.xml", true, {{true, "127.0.0.1", 0}});
  fly_over(server, "udp:127.0.0.1:" + std::to_string(server.udp_port()));
}

TEST(ClientUdp, FliesAVehicleThatSendsToTheGroundStationsPort) {
  const int gcs_port = free_udp_port();
  SimServer server("empty.xml", true, {{false, "127.0.0.1", gcs_port}});
  fly_over(server, "udpin:127.0.0.1:" + std::to_string(gcs_port));
}

TEST(ClientUdp, LinkAddressesAreParsed) {
  auto loop = EventLoop::create();
  ASSERT_TRUE(loop);
  Vehicle uav(**loop);
  const auto r = uav.connect("udpx:127.0.0.1:5", 1);
  ASSERT_FALSE(r);
  EXPECT_EQ(r.code(), Error::kInvalidArgument);
  EXPECT_NE(r.message().find("udpin:ADDR:PORT"), std::string::npos) << r.message();
}

}  // namespace
}  // namespace uavsim::client::testing
