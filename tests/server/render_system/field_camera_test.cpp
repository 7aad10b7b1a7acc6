// Camera latency (field conditions, docs/protocol.md "Camera frames"): a frame is stamped at
// exposure and delivered once sim time has reached exposure + latency. In lockstep at the frame
// period: before the tick at t the client has the frame exposed at t - latency, not the one exposed
// at t.
#include <gtest/gtest.h>

#include <cmath>
#include <optional>
#include <set>
#include <vector>

#include "frame_fixture.hpp"

namespace uavsim::server::render::testing {
namespace {

TEST(FieldCamera, LatencyDeliversAFrameOneLatencyAfterItsExposure) {
  ServerOptions o;
  o.camera_overrides = {"uav0_front:fps=10,width=160,height=120,latency_ms=100,noise=3"};
  FrameServer server(o);
  FrameClient c(server.port());
  ASSERT_TRUE(c.request({{"op", "camera_subscribe"}, {"camera", "uav0_front"}})["ok"]);
  ASSERT_TRUE(c.request({{"op", "lockstep_join"}, {"period_s", 0.1}})["ok"]);
  std::set<int64_t> stamps_us;  // frames received so far
  std::optional<int64_t>
      first_tick_us;  // frames exposed before the client joined may have been dropped
  int checked = 0;
  for (int n = 0; n < 10; ++n) {
    std::vector<Message> before;
    const Message tick = c.next_event("tick", &before);
    ASSERT_FALSE(tick.json.is_null());
    for (const Message& m : before) {
      if (m.json.value("event", "") == "frame") stamps_us.insert(m.json["stamp_us"].get<int64_t>());
    }
    const int64_t t_us = std::llround(tick.json["time"].get<double>() * 1e6);
    if (!first_tick_us) first_tick_us = t_us;
    if (t_us - 100000 >= *first_tick_us) {
      EXPECT_TRUE(stamps_us.count(t_us - 100000))
          << "the frame exposed 100 ms before tick " << t_us;
      EXPECT_FALSE(stamps_us.count(t_us))
          << "the frame exposed at tick " << t_us << " came without latency";
      ++checked;
    }
    ASSERT_TRUE(c.request({{"op", "done"}, {"tick", tick.json["tick"]}})["ok"]);
  }
  EXPECT_GE(checked, 8);
}

}  // namespace
}  // namespace uavsim::server::render::testing
