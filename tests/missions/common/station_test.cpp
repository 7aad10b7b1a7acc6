// The start every ground-station program shares (missions/common/station.cpp).
#include "uavsim/mission/station.hpp"

#include <gtest/gtest.h>

#include <string>

namespace {

// the launchers learn each UAV's station port from these lines
TEST(StartStation, AnnouncesOneLoopbackPortPerUavInOrder) {
  testing::internal::CaptureStdout();
  const auto station = uavsim::mission::start_station("gcs", 2, uavsim::client::GcsLinkConfig{});
  const std::string out = testing::internal::GetCapturedStdout();
  ASSERT_TRUE(station.has_value());
  ASSERT_EQ(station->links.size(), 2u);
  ASSERT_NE(station->program, nullptr);
  EXPECT_EQ(out,
            "gcs: uav0 link on udp:127.0.0.1:" + std::to_string(station->links[0]->local_port()) +
                "\ngcs: uav1 link on udp:127.0.0.1:" +
                std::to_string(station->links[1]->local_port()) + "\n");
  EXPECT_NE(station->links[0]->local_port(), station->links[1]->local_port());
}

}  // namespace
