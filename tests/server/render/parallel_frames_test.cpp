// Cameras rendered by several threads: the consumers get the same frames (content and metadata) in
// the same order as from one thread, and lockstep frames still gate the loop.
#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include <cmath>
#include <cstdint>
#include <fstream>
#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "render/camera_setup.hpp"
#include "render/frame_service.hpp"

namespace uavsim::server::render {
namespace {

constexpr int kControlSteps = 60;  // 0.6 s at 100 Hz: 9 frames a camera at 15 fps
constexpr double kCameraFps = 15.0;

// Four "vehicles" sliding at different speeds, each with a camera looking ahead at a green balloon
// and the other vehicles, and a world camera above: every frame differs from the one before.
constexpr char kWorldXml[] = R"(
<mujoco>
  <option gravity="0 0 0" timestep="0.01"/>
  <visual><global offwidth="160" offheight="120"/></visual>
  <asset>
    <texture name="grid" type="2d" builtin="checker" rgb1="0.45 0.5 0.45" rgb2="0.35 0.4 0.35" width="128" height="128"/>
    <material name="ground" texture="grid" texrepeat="10 10"/>
  </asset>
  <worldbody>
    <light directional="true" pos="0 0 20" dir="0.3 0.2 -1"/>
    <geom type="plane" size="30 30 0.1" material="ground"/>
    <camera name="overview" pos="0 0 25" xyaxes="1 0 0 0 1 0"/>
    <geom type="sphere" pos="12 0 2" size="0.8" rgba="0 0.9 0 1" contype="0" conaffinity="0"/>
    <body name="v0" pos="0 -3 1"><joint name="s0" type="slide" axis="1 0.1 0"/>
      <geom type="box" size="0.3 0.3 0.1" rgba="0.8 0.1 0.1 1" mass="1" contype="0" conaffinity="0"/>
      <camera name="v0_front" pos="0.4 0 0" xyaxes="0 -1 0 0 0 1"/></body>
    <body name="v1" pos="0 -1 1"><joint name="s1" type="slide" axis="1 -0.1 0"/>
      <geom type="box" size="0.3 0.3 0.1" rgba="0.1 0.1 0.8 1" mass="1" contype="0" conaffinity="0"/>
      <camera name="v1_front" pos="0.4 0 0" xyaxes="0 -1 0 0 0 1"/></body>
    <body name="v2" pos="0 1 1"><joint name="s2" type="slide" axis="1 0.05 0.02"/>
      <geom type="box" size="0.3 0.3 0.1" rgba="0.8 0.8 0.1 1" mass="1" contype="0" conaffinity="0"/>
      <camera name="v2_front" pos="0.4 0 0" xyaxes="0 -1 0 0 0 1"/></body>
    <body name="v3" pos="0 3 1"><joint name="s3" type="slide" axis="1 -0.05 0.02"/>
      <geom type="box" size="0.3 0.3 0.1" rgba="0.8 0.1 0.8 1" mass="1" contype="0" conaffinity="0"/>
      <camera name="v3_front" pos="0.4 0 0" xyaxes="0 -1 0 0 0 1"/></body>
  </worldbody>
</mujoco>
)";

// what a consumer saw of one frame, in delivery order
struct Seen {
  int camera = -1;
  int64_t index = 0;
  int64_t stamp_us = 0;
  std::string rgb, jpeg;
  Eigen::Vector3d position_enu_m;
  bool operator==(const Seen& o) const {
    return camera == o.camera && index == o.index && stamp_us == o.stamp_us && rgb == o.rgb &&
           jpeg == o.jpeg && position_enu_m == o.position_enu_m;
  }
};

// wants every frame in RGB and JPEG; lockstep (must deliver), so no frame is dropped
class Recorder : public FrameConsumer {
 public:
  void want(int, int64_t, int64_t, std::vector<EncodingKey>* encodings,
            bool* must_deliver) override {
    encodings->push_back({Encoding::kRgb, 0});
    encodings->push_back({Encoding::kJpeg, 90});
    *must_deliver = true;
  }
  void dropped(int, int64_t) override { ++dropped_; }
  void deliver(const ReadyFrame& f) override {
    Seen s;
    s.camera = f.camera;
    s.index = f.index;
    s.stamp_us = f.stamp_us;
    s.rgb = *f.image({Encoding::kRgb, 0});
    s.jpeg = *f.image({Encoding::kJpeg, 90});
    s.position_enu_m = f.position_enu_m;
    seen_.push_back(std::move(s));
  }
  std::vector<Seen> seen_;  // written on the render thread; read after wait_delivered
  int dropped_ = 0;
};

struct FrameRun {
  std::vector<Seen> seen;
  int threads = 0;
  int dropped = 0;
  std::vector<size_t> seen_at_step;  // frames delivered when each control step's capture returned
};

// runs the world for kControlSteps with `threads` render threads; queue depth 1 so that lockstep
// capture waits for the renderer at every snapshot. latent_s: the latency of the overview and
// v0_front cameras (the others have none); before_step: what the loop waits for after each capture
// (a lockstep tick's FrameService::wait_due, or wait_delivered)
enum class Wait { kDelivered, kDue };
constexpr const char* kLatentCameras[] = {"overview", "v0_front"};
FrameRun run_with(int threads, const std::string& backend = "osmesa", double latent_s = 0.0,
                  Wait before_step = Wait::kDelivered) {
  const std::string path = ::testing::TempDir() + "parallel_frames.xml";
  std::ofstream(path) << kWorldXml;
  char error[1000] = "";
  mjModel* m = mj_loadXML(path.c_str(), nullptr, error, sizeof(error));
  if (m == nullptr) throw std::runtime_error(error);
  mjData* d = mj_makeData(m);
  for (int j = 0; j < 4; ++j) d->qvel[j] = 4.0 + 2.0 * j;  // m/s along each slide

  std::vector<CameraSetup> cameras;
  for (const char* name : {"overview", "v0_front", "v1_front", "v2_front", "v3_front"}) {
    CameraSetup c;
    c.config.camera = name;
    c.config.width_px = 160;
    c.config.height_px = 120;
    c.config.fps_hz = kCameraFps;
    c.config.noise_sd = 3.0;  // field conditions: seeded per (camera, frame), not per thread
    for (const char* latent : kLatentCameras) {
      if (c.config.camera == latent) c.config.latency_s = latent_s;
    }
    cameras.push_back(c);
  }
  FrameRun run;
  {
    FrameServiceOptions options;
    options.render_threads = threads;
    options.queue_depth = 1;
    options.backend = backend;
    FrameService frames(m, cameras, options);
    run.threads = frames.render_threads();
    Recorder recorder;
    frames.add_consumer(&recorder);
    for (int step = 0; step < kControlSteps; ++step) {
      mj_forward(m, d);
      frames.capture(d);
      if (before_step == Wait::kDue) {
        frames.wait_due();
      } else {
        frames.wait_delivered();
      }
      run.seen_at_step.push_back(recorder.seen_.size());
      mj_step(m, d);
    }
    frames.wait_delivered();
    run.seen = recorder.seen_;
    run.dropped = recorder.dropped_;
  }
  mj_deleteData(d);
  mj_deleteModel(m);
  return run;
}

TEST(ParallelFrames, AssignmentSpreadsCamerasByWorkAndIsDeterministic) {
  std::vector<FrameCamera> cams(5);
  for (FrameCamera& c : cams) {
    c.width_px = 320;
    c.height_px = 240;
    c.fps_hz = 15.0;
  }
  cams[0].width_px = 640;  // the overview: twice the pixels of a vehicle camera
  cams[0].height_px = 480;
  // loads (x 320*240*15): 4, 1, 1, 1, 1 -> thread 0 takes the overview, the vehicles go to 1, 2, 1,
  // 2
  EXPECT_EQ(assign_cameras(cams, 3), (std::vector<int>{0, 1, 2, 1, 2}));
  EXPECT_EQ(assign_cameras(cams, 1), (std::vector<int>{0, 0, 0, 0, 0}));
  EXPECT_EQ(default_render_threads(0), 1);
  EXPECT_EQ(default_render_threads(1), 1);
  EXPECT_LE(default_render_threads(100), kMaxDefaultRenderThreads);
}

TEST(ParallelFrames, ThreadsDeliverTheSameFramesInTheSameOrderAsOne) {
  const FrameRun serial = run_with(1);
  const FrameRun parallel = run_with(3);
  EXPECT_EQ(serial.threads, 1);
  EXPECT_EQ(parallel.threads, 3);
  // frames k = 0..8 of 5 cameras: t = k / 15 s falls within the 0.6 s run for k <= 8
  ASSERT_EQ(serial.seen.size(), 5u * 9u);
  EXPECT_EQ(serial.dropped, 0);
  EXPECT_EQ(parallel.dropped, 0);
  ASSERT_EQ(parallel.seen.size(), serial.seen.size());
  for (size_t i = 0; i < serial.seen.size(); ++i) {
    EXPECT_TRUE(parallel.seen[i] == serial.seen[i])
        << "frame " << i << ": camera " << parallel.seen[i].camera << " #" << parallel.seen[i].index
        << " vs camera " << serial.seen[i].camera << " #" << serial.seen[i].index;
  }
  // the frames change over time (the vehicles move): equal sequences are not a blank-frame accident
  EXPECT_NE(serial.seen[1].rgb, serial.seen[6].rgb);
}

TEST(ParallelFrames, LockstepFramesAreDeliveredBeforeTheNextStepWithAnyThreadCount) {
  const FrameRun serial = run_with(1);
  const FrameRun parallel = run_with(4);
  // wait_delivered after each capture: every frame due at a step has reached the consumer by then,
  // the same count at every step
  EXPECT_EQ(parallel.seen_at_step, serial.seen_at_step);
  EXPECT_EQ(parallel.seen_at_step.back(), 5u * 9u);
}

TEST(ParallelFrames, ALockstepTickGetsEachLatentFrameAtTheFirstStepAtOrAfterItsDueTime) {
  // 50 ms of latency on two of the five cameras: wait_due, which leaves frames not yet due
  // rendering beside the next steps, delivers every frame at exactly the control step
  // wait_delivered did (never earlier, never later), with the same content, in the same order, on
  // one thread or three
  constexpr double kLatencyS = 0.05;
  const FrameRun all = run_with(1, "osmesa", kLatencyS, Wait::kDelivered);
  const FrameRun due = run_with(1, "osmesa", kLatencyS, Wait::kDue);
  const FrameRun due3 = run_with(3, "osmesa", kLatencyS, Wait::kDue);
  EXPECT_EQ(due.seen_at_step, all.seen_at_step);
  EXPECT_EQ(due3.seen_at_step, all.seen_at_step);
  ASSERT_EQ(due.seen.size(), all.seen.size());
  ASSERT_EQ(due3.seen.size(), all.seen.size());
  for (size_t i = 0; i < all.seen.size(); ++i) {
    EXPECT_TRUE(due.seen[i] == all.seen[i]) << "frame " << i;
    EXPECT_TRUE(due3.seen[i] == all.seen[i]) << "frame " << i;
  }
  // and that step is the first one at or after stamp + latency (steps are 10 ms apart, from t = 0)
  int latent_seen = 0;
  size_t first = 0;
  for (size_t step = 0; step < due.seen_at_step.size(); ++step) {
    const int64_t now_us = static_cast<int64_t>(step) * 10000;
    for (size_t i = first; i < due.seen_at_step[step]; ++i) {
      const Seen& f = due.seen[i];
      const bool latent = f.camera <= 1;  // overview, v0_front: the cameras' order in run_with
      const int64_t due_us = f.stamp_us + (latent ? std::llround(kLatencyS * 1e6) : 0);
      EXPECT_LE(due_us, now_us) << "camera " << f.camera << " #" << f.index << " came early";
      EXPECT_GT(due_us, now_us - 10000) << "camera " << f.camera << " #" << f.index << " came late";
      latent_seen += latent ? 1 : 0;
    }
    first = due.seen_at_step[step];
  }
  // all nine frames of each latent camera: the last, exposed at the step of 0.54 s, is due at the
  // last step, 0.59 s
  EXPECT_EQ(latent_seen, 2 * 9);
}

TEST(ParallelFrames, EglThreadsDeliverTheSameFramesAsOsmesaOnOne) {
  const FrameRun osmesa = run_with(1, "osmesa");
  const FrameRun egl = run_with(3, "egl");
  ASSERT_EQ(egl.seen.size(), osmesa.seen.size());
  for (size_t i = 0; i < osmesa.seen.size(); ++i) {
    EXPECT_TRUE(egl.seen[i] == osmesa.seen[i]) << "frame " << i;
  }
}

TEST(ParallelFrames, NegativeThreadCountIsRefused) {
  const std::string path = ::testing::TempDir() + "parallel_frames_refused.xml";
  std::ofstream(path) << kWorldXml;
  mjModel* m = mj_loadXML(path.c_str(), nullptr, nullptr, 0);
  ASSERT_NE(m, nullptr);
  FrameServiceOptions options;
  options.render_threads = -1;
  EXPECT_THROW(FrameService(m, {}, options), std::invalid_argument);
  mj_deleteModel(m);
}

}  // namespace
}  // namespace uavsim::server::render
