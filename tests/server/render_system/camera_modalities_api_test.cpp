// Depth and segmentation through the sim API (docs/protocol.md "Camera frames"): the images of one
// capture arrive together with one stamp and seq, before their lockstep tick as colour frames do;
// the subscribe reply carries the depth range and the segmentation's id tables; bad requests get
// clear errors.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include "frame_fixture.hpp"

namespace uavsim::server::render::testing {
namespace {

const std::string kScene = std::string(UAVSIM_TEST_DATA_DIR) + "/worlds/camera_scene.xml";

TEST(CameraModalitiesApi, CaptureSharesStampAndSeqAndPrecedesItsTick) {
  ServerOptions o;
  o.world = kScene;
  FrameServer server(o);
  FrameClient c(server.port());
  const Json sub = c.request({{"op", "camera_subscribe"},
                              {"camera", "rgbd"},
                              {"modalities", {"segmentation", "rgb", "depth"}}});
  ASSERT_TRUE(sub["ok"]) << sub;
  const Json& r = sub["result"];
  EXPECT_EQ(r["modalities"], Json({"rgb", "depth", "segmentation"}));  // in the protocol's order
  EXPECT_GT(r["depth"]["far_m"].get<double>(), r["depth"]["near_m"].get<double>());
  EXPECT_EQ(r["depth"]["invalid"], "nan");
  // the tables: classes by id, objects with their class
  std::map<std::string, int> classes, object_class;
  for (const Json& k : r["segmentation"]["classes"]) classes[k["name"]] = k["id"];
  for (const Json& obj : r["segmentation"]["objects"]) object_class[obj["name"]] = obj["class"];
  EXPECT_EQ(classes.at("none"), 0);
  EXPECT_EQ(object_class.at("b0"), classes.at("balloon"));
  EXPECT_EQ(object_class.at("b0/pole"), classes.at("pole"));
  EXPECT_EQ(object_class.at("truck"), classes.at("truck"));
  EXPECT_EQ(object_class.at("truck/marker"), classes.at("marker"));
  EXPECT_EQ(object_class.at("uav0"), classes.at("vehicle"));
  EXPECT_EQ(object_class.at("ground"), classes.at("ground"));

  ASSERT_TRUE(c.request({{"op", "lockstep_join"}, {"period_s", 0.1}})["ok"]);
  int captures = 0;
  for (int n = 0; n < 4; ++n) {
    std::vector<Message> before;
    const Message tick = c.next_event("tick", &before);
    ASSERT_FALSE(tick.json.is_null());
    const double t = tick.json["time"];
    // the frame parts before this tick: whole captures, parts in order, one stamp and seq each
    std::vector<const Message*> parts;
    for (const Message& m : before) {
      if (m.json.value("event", "") == "frame") parts.push_back(&m);
    }
    ASSERT_EQ(parts.size() % 3, 0u) << "a capture split around tick " << t;
    bool has_tick_frame = false;
    for (size_t i = 0; i < parts.size(); i += 3) {
      const Json& h0 = parts[i]->json;
      for (size_t k = 0; k < 3; ++k) {
        const Json& h = parts[i + k]->json;
        EXPECT_EQ(h["part"], k);
        EXPECT_EQ(h["parts"], 3);
        EXPECT_EQ(h["seq"], h0["seq"]);
        EXPECT_EQ(h["stamp_us"], h0["stamp_us"]);
        EXPECT_EQ(h["pose"], h0["pose"]);
        EXPECT_EQ(h["modalities"], Json({"rgb", "depth", "segmentation"}));
        EXPECT_EQ(parts[i + k]->bytes.size(), h["bytes"].get<size_t>());
      }
      const size_t pixels = 320u * 240u;
      EXPECT_EQ(parts[i]->json["format"], "rgb");
      EXPECT_EQ(parts[i]->bytes.size(), pixels * 3);
      EXPECT_EQ(parts[i + 1]->json["format"], "depth");
      EXPECT_EQ(parts[i + 1]->bytes.size(), pixels * 4);
      EXPECT_GT(parts[i + 1]->json["far_m"].get<double>(), 0.0);
      EXPECT_EQ(parts[i + 2]->json["format"], "segmentation");
      EXPECT_EQ(parts[i + 2]->bytes.size(), pixels * 4);
      // the image centre sees the ground or the truck, 20 to 40 m away
      float z = 0;
      std::memcpy(&z, parts[i + 1]->bytes.data() + 4 * (120 * 320 + 160), 4);
      EXPECT_TRUE(std::isfinite(z) && z > 5.0f && z < 60.0f) << z;
      if (std::abs(h0["stamp"].get<double>() - t) < 1e-9) has_tick_frame = true;
      ++captures;
    }
    EXPECT_TRUE(has_tick_frame) << "no capture stamped " << t << " before its tick";
    ASSERT_TRUE(c.request({{"op", "done"}, {"tick", tick.json["tick"]}})["ok"]);
  }
  EXPECT_GE(captures, 3);
}

TEST(CameraModalitiesApi, BadRequestsGetClearErrors) {
  ServerOptions o;
  o.world = kScene;
  o.camera_overrides = {"above:width=1920,height=1080"};
  FrameServer server(o);
  FrameClient c(server.port());
  const Json list = c.request({{"op", "camera_list"}});
  ASSERT_TRUE(list["ok"]) << list;
  for (const Json& cam : list["result"]["cameras"]) {
    if (cam["name"] == "rgbd")
      EXPECT_EQ(cam["modalities"], Json({"rgb", "grey", "depth", "segmentation"}));
    if (cam["name"] == "plain") EXPECT_EQ(cam["modalities"], Json({"rgb", "grey"}));
    if (cam["name"] == "above") EXPECT_EQ(cam["formats"], Json({"rgb", "jpeg"}));
  }
  auto error = [&](Json req) {
    req["op"] = "camera_subscribe";
    const Json r = c.request(req);
    EXPECT_FALSE(r["ok"]) << r;
    EXPECT_EQ(r["error"]["code"], "bad_field") << r;
    return r["error"]["message"].get<std::string>();
  };
  EXPECT_NE(error({{"camera", "rgbd"}, {"modalities", {"rgb", "thermal"}}}).find("thermal"),
            std::string::npos);
  EXPECT_NE(error({{"camera", "rgbd"}, {"modalities", "depth"}}).find("list"), std::string::npos);
  EXPECT_NE(error({{"camera", "rgbd"}, {"modalities", Json::array()}}).find("list"),
            std::string::npos);
  EXPECT_NE(error({{"camera", "rgbd"}, {"modalities", {"depth", "depth"}}}).find("twice"),
            std::string::npos);
  EXPECT_NE(error({{"camera", "rgbd"}, {"modalities", {"depth", 3}}}).find("unknown"),
            std::string::npos);
  EXPECT_NE(
      error({{"camera", "rgbd"}, {"format", "rgb"}, {"modalities", {"depth"}}}).find("not both"),
      std::string::npos);
  Json many = Json::array();
  for (int i = 0; i < 100; ++i) many.push_back("rgb");
  EXPECT_NE(error({{"camera", "rgbd"}, {"modalities", many}}).find("list"), std::string::npos);
  // what the camera does not give
  EXPECT_NE(error({{"camera", "plain"}, {"modalities", {"rgb", "depth"}}}).find("gives no depth"),
            std::string::npos);
  EXPECT_NE(error({{"camera", "plain"}, {"format", "segmentation"}}).find("gives no segmentation"),
            std::string::npos);
  EXPECT_NE(error({{"camera", "above"}, {"format", "grey"}}).find("gives no grey"),
            std::string::npos);
  EXPECT_NE(error({{"camera", "rgbd"}, {"modalities", {"depth"}}, {"quality", 80}}).find("jpeg"),
            std::string::npos);
  // too large: 1920 x 1080 x (3 + 4 + 4) bytes is over the 20 MiB a capture may have; RGB alone is
  // not
  EXPECT_NE(error({{"camera", "above"}, {"modalities", {"rgb", "depth", "segmentation"}}})
                .find("too large"),
            std::string::npos);
  const Json rgb_only =
      c.request({{"op", "camera_subscribe"}, {"camera", "above"}, {"format", "rgb"}});
  EXPECT_TRUE(rgb_only["ok"]) << rgb_only;
  // one modality alone, and JPEG with depth
  const Json depth =
      c.request({{"op", "camera_subscribe"}, {"camera", "rgbd"}, {"format", "depth"}});
  ASSERT_TRUE(depth["ok"]) << depth;
  EXPECT_EQ(depth["result"]["modalities"], Json({"depth"}));
  EXPECT_TRUE(depth["result"].contains("depth"));
  EXPECT_FALSE(depth["result"].contains("segmentation"));
  const Json jd = c.request({{"op", "camera_subscribe"},
                             {"camera", "rgbd"},
                             {"modalities", {"depth", "jpeg"}},
                             {"quality", 70}});
  ASSERT_TRUE(jd["ok"]) << jd;
  EXPECT_EQ(jd["result"]["quality"], 70);
  EXPECT_EQ(jd["result"]["modalities"], Json({"jpeg", "depth"}));
}

}  // namespace
}  // namespace uavsim::server::render::testing
