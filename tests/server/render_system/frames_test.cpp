// System tests of camera frames through the sim API (docs/protocol.md "Camera frames"): geometry of what
// the cameras show (a balloon at the pixel and size the intrinsics predict), stamps that match the pose
// shown, back-pressure (a reader that does not read loses frames, sim time does not slow), error replies,
// the MAVLink gimbal commands seen by a camera, and the MAVLink endpoint hooks (link drop, lockstep seq).
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "frame_fixture.hpp"
#include "mav_client.hpp"
#include "physics/object_bodies.hpp"
#include "uavsim/common/angles.hpp"

namespace uavsim::server::render::testing {
namespace {

constexpr double kBalloonRadiusM = 0.3;
constexpr double kBalloonAboveBodyM = 2.7;
constexpr double kTimeTol_s = 1e-9;
constexpr double kFocalTol_px = 1e-6;
constexpr double kPeriodTol_s = 0.0021;
constexpr double kAxisTol = 1e-3;
constexpr double kCentreTol_px = 2.0;
constexpr double kRadiusRelTol = 0.05;
constexpr double kRadiusTol_px = 1.0;
constexpr double kTrackTol_px = 1.5;
constexpr double kPitchTol_deg = 1e-6;
constexpr double kRtlDelayTol_s = 0.5;

// centroid and equivalent radius of the balloon-green pixels of an RGB image
struct Blob {
  double u = 0, v = 0, radius_px = 0;
  int pixels = 0;
};
Blob green_blob(const std::string& rgb, int w, int h) {
  Blob b;
  double su = 0, sv = 0;
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const auto* p = reinterpret_cast<const uint8_t*>(rgb.data()) + 3 * (static_cast<size_t>(y) * w + x);
      if (p[1] > p[0] + 12 && p[1] > p[2] + 12) {
        su += x;
        sv += y;
        ++b.pixels;
      }
    }
  }
  if (b.pixels > 0) {
    b.u = su / b.pixels;
    b.v = sv / b.pixels;
    b.radius_px = std::sqrt(b.pixels / common::kPi);
  }
  return b;
}

Eigen::Vector3d vec(const Json& j) { return {j[0].get<double>(), j[1].get<double>(), j[2].get<double>()}; }
Eigen::Matrix3d mat(const Json& j) {
  Eigen::Matrix3d R;
  for (int i = 0; i < 3; ++i)
    for (int k = 0; k < 3; ++k) R(i, k) = j[3 * i + k].get<double>();
  return R;
}

// moves balloon `name` so that its sphere's centre is at c (loop held)
void place_balloon(sim::Simulation& sim, const std::string& name, const Eigen::Vector3d& c) {
  const int body = sim.world().body_id(name);
  ASSERT_GE(body, 0) << name;
  ASSERT_TRUE(physics::set_mocap_pose(sim.world(), body, c - Eigen::Vector3d(0, 0, kBalloonAboveBodyM),
                                      Eigen::Quaterniond::Identity()));
}
void clear_other_balloons(sim::Simulation& sim) {
  for (int k = 1; k < 5; ++k) place_balloon(sim, "b" + std::to_string(k), {200.0 + 10 * k, -200.0, 3.0});
}

Message next_frame(FrameClient& c) {
  for (;;) {
    Message m = c.next_event("frame");
    if (m.json.is_null() || m.json.value("event", "") == "frame") return m;
  }
}

TEST(FramesApi, CameraListAndErrorReplies) {
  FrameServer server;
  FrameClient c(server.port());
  const Json list = c.request({{"op", "camera_list"}});
  ASSERT_TRUE(list["ok"]) << list;
  ASSERT_EQ(list["result"]["cameras"].size(), 3u) << list;
  std::map<std::string, Json> cams;
  for (const Json& cam : list["result"]["cameras"]) cams[cam["name"]] = cam;
  ASSERT_EQ(cams.size(), 3u);
  EXPECT_EQ(cams["uav0_front"]["vehicle"], "uav0");
  EXPECT_EQ(cams["uav0_front"]["vehicle_index"], 0);
  EXPECT_EQ(cams["uav1_front"]["vehicle"], "uav1");
  EXPECT_TRUE(cams["overview"]["vehicle"].is_null());
  EXPECT_TRUE(cams["overview"]["vehicle_index"].is_null());
  EXPECT_EQ(cams["uav0_front"]["width"], 640);
  EXPECT_EQ(cams["uav0_front"]["height"], 480);
  EXPECT_DOUBLE_EQ(cams["uav0_front"]["fps"].get<double>(), 15.0);
  EXPECT_NEAR(cams["uav0_front"]["intrinsics"]["fy"].get<double>(),
              240.0 / std::tan(11.0 * common::kPi / 180.0), kFocalTol_px);
  EXPECT_DOUBLE_EQ(cams["uav0_front"]["intrinsics"]["cx"].get<double>(), 319.5);
  EXPECT_EQ(cams["overview"]["formats"], Json({"rgb", "grey", "jpeg"}));

  auto code = [&](const Json& req) {
    const Json r = c.request(req);
    EXPECT_FALSE(r["ok"]) << r;
    return r["error"]["code"].get<std::string>();
  };
  EXPECT_EQ(code({{"op", "camera_subscribe"}}), "missing_field");
  EXPECT_EQ(code({{"op", "camera_subscribe"}, {"camera", "nope"}}), "bad_field");
  EXPECT_EQ(code({{"op", "camera_subscribe"}, {"camera", 3}}), "bad_field");
  EXPECT_EQ(code({{"op", "camera_subscribe"}, {"camera", "uav0_front"}, {"format", "png"}}), "bad_field");
  EXPECT_EQ(code({{"op", "camera_subscribe"}, {"camera", "uav0_front"}, {"fps", 30}}), "bad_field");
  EXPECT_EQ(code({{"op", "camera_subscribe"}, {"camera", "uav0_front"}, {"fps", 4}}), "bad_field");
  EXPECT_EQ(code({{"op", "camera_subscribe"}, {"camera", "uav0_front"}, {"fps", -1}}), "bad_field");
  // one frame in 1.5e301 once became every = INT_MIN (an undefined float-to-int cast)
  EXPECT_EQ(code({{"op", "camera_subscribe"}, {"camera", "uav0_front"}, {"fps", 1e-300}}), "bad_field");
  EXPECT_EQ(code({{"op", "camera_subscribe"}, {"camera", "uav0_front"}, {"fps", 15.0 / 3e9}}), "bad_field");
  EXPECT_EQ(code({{"op", "camera_subscribe"}, {"camera", "uav0_front"}, {"quality", 50}}), "bad_field");
  EXPECT_EQ(code({{"op", "camera_subscribe"}, {"camera", "uav0_front"}, {"format", "jpeg"}, {"quality", 0}}),
            "bad_field");
  EXPECT_EQ(code({{"op", "camera_unsubscribe"}, {"camera", "nope"}}), "bad_field");
  const Json ok = c.request({{"op", "camera_subscribe"}, {"camera", "uav0_front"}, {"fps", 5}});
  ASSERT_TRUE(ok["ok"]) << ok;
  EXPECT_EQ(ok["result"]["every"], 3);
  const Json un = c.request({{"op", "camera_unsubscribe"}, {"camera", "uav1_front"}});
  EXPECT_EQ(un["result"]["subscribed"], false);
}

TEST(FramesApi, FormatsLayoutStampsAndSeq) {
  ServerOptions o;
  o.camera_overrides = {"*:width=320,height=240"};
  FrameServer server(o);
  FrameClient c(server.port());
  ASSERT_TRUE(c.request({{"op", "camera_subscribe"}, {"camera", "uav0_front"}})["ok"]);
  ASSERT_TRUE(c.request({{"op", "camera_subscribe"}, {"camera", "uav1_front"}, {"format", "grey"}})["ok"]);
  ASSERT_TRUE(c.request({{"op", "camera_subscribe"}, {"camera", "overview"}, {"format", "jpeg"},
                         {"quality", 80}, {"fps", 7.5}})["ok"]);
  // in lockstep no frame is dropped (the clock waits for the renderer), however loaded the machine:
  // the frames from the first tick on must have consecutive seqs
  ASSERT_TRUE(c.request({{"op", "lockstep_join"}, {"period_s", 0.1}})["ok"]);
  bool ticked = false;  // frames before the first tick may have been dropped: those are not checked
  std::map<std::string, std::vector<Json>> seen;
  while (seen["overview"].size() < 3) {
    const Message m = c.read();
    ASSERT_FALSE(m.json.is_null()) << "no frame or tick";
    if (m.json.value("event", "") == "tick") {
      ticked = true;
      ASSERT_TRUE(c.request({{"op", "done"}, {"tick", m.json["tick"]}})["ok"]);
      continue;
    }
    if (m.json.value("event", "") != "frame" || !ticked) continue;
    const Json& h = m.json;
    const std::string cam = h["camera"];
    EXPECT_EQ(m.bytes.size(), h["bytes"].get<size_t>());
    const int w = h["width"], hh = h["height"];
    if (cam == "uav0_front") {
      EXPECT_EQ(h["format"], "rgb");
      EXPECT_EQ(m.bytes.size(), static_cast<size_t>(w * hh * 3));
    } else if (cam == "uav1_front") {
      EXPECT_EQ(h["format"], "grey");
      EXPECT_EQ(m.bytes.size(), static_cast<size_t>(w * hh));
    } else {
      EXPECT_EQ(h["format"], "jpeg");
      const cv::Mat img = cv::imdecode(std::vector<uint8_t>(m.bytes.begin(), m.bytes.end()), cv::IMREAD_COLOR);
      EXPECT_EQ(img.cols, w);
      EXPECT_EQ(img.rows, hh);
    }
    // stamps are control-step times (500 Hz)
    const int64_t us = h["stamp_us"];
    EXPECT_EQ(us % 2000, 0) << h;
    EXPECT_NEAR(h["stamp"].get<double>(), us * 1e-6, kTimeTol_s);
    EXPECT_EQ(h["pose"]["R_enu_cam"].size(), 9u);
    seen[cam].push_back(h);
  }
  for (const auto& [cam, hs] : seen) {
    const double period = cam == "overview" ? 2.0 / 15.0 : 1.0 / 15.0;
    for (size_t k = 1; k < hs.size(); ++k) {
      EXPECT_EQ(hs[k]["seq"].get<int>(), hs[k - 1]["seq"].get<int>() + 1) << cam;
      const double dt = hs[k]["stamp"].get<double>() - hs[k - 1]["stamp"].get<double>();
      EXPECT_NEAR(dt, period, kPeriodTol_s) << cam;
    }
  }
}

// a balloon placed at a known point in front of uav0's forward camera shows where the intrinsics say
TEST(FramesAcceptance, BalloonAtPredictedPixelAndSize) {
  ServerOptions o;
  o.start_paused = true;
  FrameServer server(o);
  FrameClient c(server.port());
  ASSERT_TRUE(c.request({{"op", "camera_subscribe"}, {"camera", "uav0_front"}})["ok"]);
  ASSERT_TRUE(c.request({{"op", "step"}, {"duration_s", 0.1}})["ok"]);
  const Message first = next_frame(c);
  ASSERT_FALSE(first.json.is_null());
  const Eigen::Vector3d cam = vec(first.json["pose"]["position_enu_m"]);
  const Eigen::Matrix3d R = mat(first.json["pose"]["R_enu_cam"]);
  // forward gimbal of a vehicle heading north: the optical axis is north, level
  EXPECT_NEAR(R.col(2).y(), 1.0, kAxisTol);
  const Json& k = first.json["intrinsics"];
  const double fx = k["fx"], fy = k["fy"], cx = k["cx"], cy = k["cy"];

  for (const Eigen::Vector3d& p_cam : {Eigen::Vector3d(0.6, -0.5, 12.0), Eigen::Vector3d(-0.9, -0.8, 8.0)}) {
    // the loop is held (paused, the step has been answered): place the balloons
    const double moved_at = c.request({{"op", "status"}})["result"]["time_s"];
    clear_other_balloons(server.sim());
    place_balloon(server.sim(), "b0", cam + R * p_cam);
    ASSERT_TRUE(c.request({{"op", "step"}, {"duration_s", 0.1}})["ok"]);
    // the first frame taken after the move (frames arrive asynchronously, maybe after the step's reply)
    Message m;
    do {
      m = next_frame(c);
      ASSERT_FALSE(m.json.is_null());
    } while (m.json["stamp"].get<double>() <= moved_at + 1e-9);
    const Blob b = green_blob(m.bytes, m.json["width"], m.json["height"]);
    if (std::getenv("UAVSIM_DUMP")) {
      cv::Mat img(480, 640, CV_8UC3, const_cast<char*>(m.bytes.data()));
      cv::Mat bgr;
      cv::cvtColor(img, bgr, cv::COLOR_RGB2BGR);
      cv::imwrite("/tmp/balloon_" + std::to_string(p_cam.z()) + ".png", bgr);
    }
    ASSERT_GT(b.pixels, 100);
    const double u = fx * p_cam.x() / p_cam.z() + cx;
    const double v = fy * p_cam.y() / p_cam.z() + cy;
    EXPECT_NEAR(b.u, u, kCentreTol_px) << "balloon at " << p_cam.transpose();
    EXPECT_NEAR(b.v, v, kCentreTol_px) << "balloon at " << p_cam.transpose();
    // apparent radius of a sphere: f r / sqrt(Z^2 - r^2)
    const double r_px = fy * kBalloonRadiusM / std::sqrt(p_cam.squaredNorm() - kBalloonRadiusM * kBalloonRadiusM);
    EXPECT_NEAR(b.radius_px, r_px, kRadiusRelTol * r_px + kRadiusTol_px);
  }
}

// a frame's stamp is the sim time of what it shows: in lockstep the test moves the balloon at every tick,
// and the frame stamped t shows where the balloon was put for t
TEST(FramesAcceptance, StampMatchesThePoseShownAndFramesPrecedeTheirTick) {
  ServerOptions o;
  o.camera_overrides = {"uav0_front:fps=10,width=320,height=240"};
  FrameServer server(o);
  FrameClient c(server.port());
  ASSERT_TRUE(c.request({{"op", "camera_subscribe"}, {"camera", "uav0_front"}})["ok"]);
  const Json join = c.request({{"op", "lockstep_join"}, {"period_s", 0.1}});
  ASSERT_TRUE(join["ok"]) << join;
  Eigen::Vector3d cam;
  Eigen::Matrix3d R;
  double fx = 0, cx = 0;
  auto lateral = [](double t) { return -1.0 + 0.25 * std::fmod(std::round(t * 10.0), 8.0); };
  std::optional<double> placed_for;
  int checked = 0;
  for (int n = 0; n < 12; ++n) {
    // everything up to the tick event: the frame of this tick must be among it
    std::vector<Message> before;
    const Message tick = c.next_event("tick", &before);
    ASSERT_FALSE(tick.json.is_null());
    const double t = tick.json["time"];
    std::optional<Message> frame;
    for (const Message& m : before) {
      if (m.json.value("event", "") == "frame" && std::abs(m.json["stamp"].get<double>() - t) < 1e-9) frame = m;
    }
    ASSERT_TRUE(frame.has_value()) << "no frame stamped " << t << " before its tick";
    if (frame) {
      cam = vec(frame->json["pose"]["position_enu_m"]);
      R = mat(frame->json["pose"]["R_enu_cam"]);
      fx = frame->json["intrinsics"]["fx"];
      cx = frame->json["intrinsics"]["cx"];
      if (placed_for && std::abs(*placed_for - t) < 1e-9) {
        const Blob b = green_blob(frame->bytes, 320, 240);
        ASSERT_GT(b.pixels, 20);
        EXPECT_NEAR(b.u, fx * lateral(t) / 10.0 + cx, kTrackTol_px) << "frame stamped " << t;
        ++checked;
      }
    }
    if (fx > 0) {
      // for the next tick's frame
      clear_other_balloons(server.sim());
      place_balloon(server.sim(), "b0", cam + R * Eigen::Vector3d(lateral(t + 0.1), 0.0, 10.0));
      placed_for = t + 0.1;
    }
    ASSERT_TRUE(c.request({{"op", "done"}, {"tick", tick.json["tick"]}})["ok"]);
  }
  EXPECT_GE(checked, 8);
}

// A camera subscriber that joins lockstep gets its first tick after the join's sim time: the frames of
// that time were captured at the start of the step, before the API ran, when it was not yet a lockstep
// client (none for it here, where it subscribed while the clock was held at 0; under load such frames
// were dropped as a free-running subscriber's). A client without subscriptions may tick at once.
TEST(FramesAcceptance, ASubscriberJoiningLockstepGetsTheFrameOfEachTickBeforeIt) {
  ServerOptions o;
  o.camera_overrides = {"uav0_front:fps=10,width=320,height=240"};
  o.start_paused = true;
  FrameServer server(o);
  FrameClient plain(server.port());
  const Json plain_join = plain.request({{"op", "lockstep_join"}, {"period_s", 0.1}});
  ASSERT_TRUE(plain_join["ok"]) << plain_join;
  EXPECT_EQ(plain_join["result"]["first_tick_time"].get<double>(), 0.0);
  ASSERT_TRUE(plain.request({{"op", "lockstep_leave"}})["ok"]);

  FrameClient c(server.port());
  ASSERT_TRUE(c.request({{"op", "camera_subscribe"}, {"camera", "uav0_front"}})["ok"]);
  const Json join = c.request({{"op", "lockstep_join"}, {"period_s", 0.1}});
  ASSERT_TRUE(join["ok"]) << join;
  EXPECT_NEAR(join["result"]["first_tick_time"].get<double>(), 0.1, kTimeTol_s);
  ASSERT_TRUE(c.request({{"op", "resume"}})["ok"]);
  for (int n = 0; n < 3; ++n) {
    std::vector<Message> before;
    const Message tick = c.next_event("tick", &before);
    ASSERT_FALSE(tick.json.is_null());
    std::vector<double> stamps;
    for (const Message& m : before) {
      if (m.json.value("event", "") != "frame") continue;
      stamps.push_back(m.json["stamp"].get<double>());
      EXPECT_EQ(m.json["dropped"].get<int>(), 0) << m.json;
    }
    const double t = tick.json["time"];
    EXPECT_NEAR(t, 0.1 * (n + 1), kTimeTol_s);
    ASSERT_EQ(stamps.size(), 1u) << "frames before the tick at " << t;
    EXPECT_NEAR(stamps[0], t, kTimeTol_s);
    ASSERT_TRUE(c.request({{"op", "done"}, {"tick", tick.json["tick"]}})["ok"]);
  }
}

// a subscriber that never reads loses frames; the clock does not slow down for it
TEST(FramesAcceptance, NonReaderDropsFramesWithoutSlowingSimTime) {
  // as fast as possible: a reader that never reads must not hold the clock, so sim time reaches 20 s
  // (the wall-clock bound only keeps a broken server from hanging the test)
  constexpr double kSimTargetS = 20.0;
  constexpr double kWallBoundS = 120.0;
  ServerOptions o;
  o.rate = 0.0;
  FrameServer server(o);
  FrameClient stuck(server.port(), 8192);
  FrameClient probe(server.port());
  for (const char* cam : {"uav0_front", "uav1_front", "overview"}) {
    ASSERT_TRUE(stuck.request({{"op", "camera_subscribe"}, {"camera", cam}})["ok"]);
  }
  const auto w0 = std::chrono::steady_clock::now();
  double t = 0.0;
  while (t < kSimTargetS &&
         std::chrono::duration<double>(std::chrono::steady_clock::now() - w0).count() < kWallBoundS) {
    t = probe.request({{"op", "status"}})["result"]["time_s"];
  }
  ASSERT_GE(t, kSimTargetS) << "the clock stalled behind a reader that does not read";
  // now read: the unsubscribe reply counts what was lost
  const Json r = stuck.request({{"op", "camera_unsubscribe"}, {"camera", "overview"}});
  ASSERT_TRUE(r["ok"]) << r;
  EXPECT_TRUE(r["result"]["subscribed"]);
  EXPECT_GT(r["result"]["dropped"].get<int>(), 10) << r;
  // reading again, the frames of the other subscriptions arrive and say what was lost: seq gaps, dropped
  // (seq + 1 = delivered + dropped: between two delivered frames, the seq gap is the dropped count's growth)
  bool saw_drop = false;
  int64_t last_seq = -1, last_dropped = -1;
  for (int k = 0; k < 100 && !saw_drop; ++k) {
    const Message m = next_frame(stuck);
    ASSERT_FALSE(m.json.is_null());
    if (m.json["camera"] != "uav0_front") continue;
    const int64_t seq = m.json["seq"];
    const int64_t dropped = m.json["dropped"];
    if (dropped > 0) saw_drop = true;
    if (last_seq >= 0) EXPECT_EQ(seq - last_seq - 1, dropped - last_dropped) << m.json;
    last_seq = seq;
    last_dropped = dropped;
  }
  EXPECT_TRUE(saw_drop);
}

// MAV_CMD_DO_MOUNT_CONTROL pitch -90 turns uav0's forward gimbal to look straight down
TEST(FramesMavlink, MountControlPitchDownTurnsTheCameraDown) {
  ServerOptions o;
  o.mavlink = true;
  o.rate = 1.0;
  FrameServer server(o);
  FrameClient c(server.port());
  MavClient mav(server.mavlink_port(0));
  ASSERT_TRUE(mav.connected());
  ASSERT_TRUE(c.request({{"op", "camera_subscribe"}, {"camera", "uav0_front"}, {"format", "grey"}})["ok"]);
  Message m = next_frame(c);
  ASSERT_FALSE(m.json.is_null());
  EXPECT_NEAR(mat(m.json["pose"]["R_enu_cam"]).col(2).y(), 1.0, kAxisTol)
      << "forward: looking north";
  mav.command(205, {-90, 0, 0, 0, 0, 0, 2});  // pitch -90, MAV_MOUNT_MODE_MAVLINK_TARGETING
  bool down = false;
  for (int k = 0; k < 30 && !down; ++k) {
    m = next_frame(c);
    ASSERT_FALSE(m.json.is_null());
    down = mat(m.json["pose"]["R_enu_cam"]).col(2).z() < -0.999;
  }
  EXPECT_TRUE(down) << "the optical axis never pointed down";
  // the API reports the MAVLink pointing
  const Json g = c.request({{"op", "gimbal"}, {"gimbal", "uav0_gimbal"}});
  EXPECT_EQ(g["result"]["mode"], "targets");
  EXPECT_NEAR(g["result"]["pitch_deg"].get<double>(), -90.0, kPitchTol_deg);
  // NEUTRAL: level and straight ahead again
  mav.command(205, {0, 0, 0, 0, 0, 0, 1});
  bool forward = false;
  for (int k = 0; k < 30 && !forward; ++k) {
    m = next_frame(c);
    forward = !m.json.is_null() && mat(m.json["pose"]["R_enu_cam"]).col(2).y() > 0.999;
  }
  EXPECT_TRUE(forward);
}

// the lockstep done's mavlink_seq: a MAVLink command sent right before done takes effect at that tick
TEST(EndpointHooks, CommandSentBeforeDoneTakesEffectAtThatTick) {
  ServerOptions o;
  o.mavlink = true;
  FrameServer server(o);
  FrameClient c(server.port());
  MavClient mav(server.mavlink_port(0));
  ASSERT_TRUE(mav.connected());
  ASSERT_TRUE(c.request({{"op", "lockstep_join"}, {"period_s", 0.002}})["ok"]);
  Json tick = c.next_event("tick").json;
  for (int n = 1; n <= 40; ++n) {
    const uint8_t seq = mav.command(205, {static_cast<float>(-n), 0, 0, 0, 0, 0, 2});
    const Json done = c.request({{"op", "done"}, {"tick", tick["tick"]}, {"mavlink_seq", {{"0", seq}}}});
    ASSERT_TRUE(done["ok"]) << done;
    EXPECT_TRUE(done["result"]["mavlink_seq_checked"]);
    tick = c.next_event("tick").json;
    ASSERT_FALSE(tick.is_null());
    // one control step later the command has been applied
    const Json g = c.request({{"op", "gimbal"}, {"gimbal", "uav0_gimbal"}});
    ASSERT_NEAR(g["result"]["pitch_deg"].get<double>(), -n, kPitchTol_deg)
        << "command " << n << " was late";
  }
}

// link_drop cuts the vehicle's MAVLink link: no GCS heartbeat arrives, the GCS failsafe (FS_GCS_ENABLE=1) RTLs
TEST(EndpointHooks, LinkDropTriggersTheGcsFailsafe) {
  ServerOptions o;
  o.mavlink = true;
  FrameServer server(o);
  FrameClient c(server.port());
  MavClient mav(server.mavlink_port(0));
  ASSERT_TRUE(mav.connected());
  ASSERT_TRUE(c.request({{"op", "lockstep_join"}, {"period_s", 0.1}})["ok"]);
  auto vehicle = [&] { return c.request({{"op", "vehicles"}})["result"]["vehicles"][0]; };
  bool link_up = true;
  double dropped_at = -1, rtl_at = -1;
  double t = 0;
  for (int n = 0; n < 400 && rtl_at < 0; ++n) {
    const Json tick = c.next_event("tick").json;
    ASSERT_FALSE(tick.is_null());
    t = tick["time"];
    uint8_t seq = mav.heartbeat();
    const Json v = vehicle();
    if (link_up && t >= 4.0 && !v["armed"].get<bool>()) {
      mav.param_set("FS_GCS_ENABLE", 1.0f);
      mav.command(176, {1, 4});  // GUIDED
      seq = mav.command(400, {1});  // arm
    } else if (link_up && v["armed"].get<bool>() && v["mode"] == "GUIDED" &&
               v["position_enu_m"][2].get<double>() < 1.0 && t < 20.0) {
      seq = mav.command(22, {0, 0, 0, 0, 0, 0, 5});  // take off to 5 m
    } else if (link_up && v["position_enu_m"][2].get<double>() > 3.0) {
      ASSERT_EQ(v["mode"], "GUIDED");
      const Json r = c.request({{"op", "link_drop"}, {"vehicle", 0}, {"down", true}});
      ASSERT_TRUE(r["ok"]) << r;
      link_up = false;
      dropped_at = t;
    }
    if (!link_up && v["mode"] == "RTL") rtl_at = t;
    Json done = {{"op", "done"}, {"tick", tick["tick"]}};
    if (link_up) done["mavlink_seq"] = {{"0", seq}};  // while down nothing is handled
    ASSERT_TRUE(c.request(done)["ok"]);
  }
  ASSERT_GT(dropped_at, 0) << "never took off (t = " << t << ")";
  ASSERT_GT(rtl_at, 0) << "no RTL after the link drop at " << dropped_at;
  // FS_GCS_TIMEOUT 5 s after the last heartbeat
  EXPECT_NEAR(rtl_at - dropped_at, 5.0, kRtlDelayTol_s);
  ASSERT_TRUE(c.request({{"op", "link_drop"}, {"vehicle", 0}, {"down", false}})["ok"]);
}

}  // namespace
}  // namespace uavsim::server::render::testing
