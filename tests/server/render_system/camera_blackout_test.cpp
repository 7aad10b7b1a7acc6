// The camera-blackout fault (docs/protocol.md "Fault injection"): frames keep their timing and size
// but every pixel is black for the requested span of sim time; then the picture comes back.
#include <gtest/gtest.h>

#include <algorithm>
#include <string>

#include "frame_fixture.hpp"

namespace uavsim::server::render::testing {
namespace {

constexpr double kTimeTol_s = 1e-9;

bool all_black(const std::string& bytes) {
  return std::all_of(bytes.begin(), bytes.end(), [](char c) { return c == 0; });
}

TEST(CameraBlackout, FramesAreBlackForTheDurationThenThePictureComesBack) {
  ServerOptions o;
  o.world = "mbzirc2017.xml";
  o.rate = 1.0;  // real time: the renderer keeps up, no frame is dropped
  o.camera_overrides = {"*:width=160,height=120,fps=10"};
  FrameServer server(o);
  FrameClient c(server.port());
  ASSERT_TRUE(
      c.request({{"op", "camera_subscribe"}, {"camera", "overview"}, {"format", "grey"}})["ok"]);
  const Json r =
      c.request({{"op", "camera_blackout"}, {"camera", "overview"}, {"duration_s", 0.5}});
  ASSERT_TRUE(r["ok"]) << r;
  const double from = r["result"]["from_s"], until = r["result"]["until_s"];
  EXPECT_NEAR(until - from, 0.5, kTimeTol_s);
  int black = 0, lit_after = 0;
  // read frames until the overview's stamps pass the blackout's end by half a second
  for (;;) {
    Message m;
    do {
      m = c.next_event("frame");
      ASSERT_FALSE(m.json.is_null()) << "no frame";
    } while (m.json.value("event", "") != "frame");
    const double stamp = m.json["stamp"];
    if (stamp >= from && stamp < until - 1e-9) {
      EXPECT_TRUE(all_black(m.bytes)) << "stamp " << stamp;
      ++black;
    } else if (stamp >= until) {
      EXPECT_FALSE(all_black(m.bytes)) << "stamp " << stamp;
      ++lit_after;
    }
    if (stamp > until + 0.5) break;
  }
  EXPECT_GE(black, 4);  // 0.5 s at 10 frames/s
  EXPECT_GE(lit_after, 4);
}

TEST(CameraBlackout, BadRequestsAreErrors) {
  ServerOptions o;
  o.world = "mbzirc2017.xml";
  FrameServer server(o);
  FrameClient c(server.port());
  EXPECT_EQ(c.request({{"op", "camera_blackout"}, {"duration_s", 1}})["error"]["code"],
            "missing_field");
  EXPECT_EQ(
      c.request(
          {{"op", "camera_blackout"}, {"camera", "nope"}, {"duration_s", 1}})["error"]["code"],
      "bad_field");
  EXPECT_EQ(c.request({{"op", "camera_blackout"}, {"camera", "overview"}})["error"]["code"],
            "missing_field");
  for (const Json& bad : {Json(-1), Json(1e9), Json("1"), Json(nullptr)}) {
    EXPECT_EQ(c.request({{"op", "camera_blackout"},
                         {"camera", "overview"},
                         {"duration_s", bad}})["error"]["code"],
              "bad_field")
        << bad;
  }
}

}  // namespace
}  // namespace uavsim::server::render::testing
