// FrameService: camera frames for whoever subscribes (the sim API's connections, the video recorder), taken
// at control steps and rendered off the loop thread (docs/protocol.md "Camera frames").
//
//   loop thread   capture(d) at every control step (in the runner's gate, before the step): for each camera
//                 whose frame k is due (the first control step at or after k / fps) it asks the consumers
//                 which encodings they want; if any, it snapshots the state (time, qpos, qvel, act, mocap,
//                 geom colours and groups: gimbals, trucks and popped balloons included) into a bounded
//                 queue. A full queue drops the frame (FrameConsumer::dropped) unless a consumer needs it
//                 (lockstep): then the loop thread waits for room. Physics otherwise never waits.
//   render threads  a pool of render_threads(); each owns a CameraRenderer with its own GL context, its own
//                 mjModel copy (offscreen buffer sized for its cameras) and its own mjData, and renders a
//                 fixed share of the cameras (assign_cameras). The first, the render thread, takes the
//                 snapshots in order; per snapshot every thread with a camera due copies the state in,
//                 mj_forward's, renders and encodes (RGB, grey, JPEG via OpenCV; depth and segmentation
//                 from a second pass, only where a job asks for them) its cameras in parallel with the
//                 others, and the render thread then hands the frames to the consumers in the
//                 snapshot's camera order. So consumers see the same frames in the same order for any
//                 thread count; only the wall time differs.
//
// This header does not include MuJoCo: users outside render/ see only forward declarations.
#pragma once

#include <Eigen/Core>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "render/modalities.hpp"
#include "render/segmentation.hpp"

struct mjModel_;
struct mjData_;

namespace uavsim::server::render {

struct CameraSetup;
class CameraDirector;

// kDepth: float32 metres along the optical axis per pixel (little-endian, NaN: nothing measured);
// kSegmentation: per pixel a uint16 object id then a uint16 class id (little-endian; 0: nothing)
enum class Encoding : uint8_t { kRgb, kGrey, kJpeg, kDepth, kSegmentation };
const char* encoding_name(Encoding e);  // "rgb", "grey", "jpeg", "depth", "segmentation"
std::optional<Encoding> encoding_from_name(const std::string& name);
// Whether an encoding is of the colour image (rgb, grey, jpeg), not of the depth and segmentation pass.
bool is_colour(Encoding e);
// Whether a camera with modalities m gives images of encoding e (JPEG is of its colour image).
bool gives(const Modalities& m, Encoding e);
// Bytes per pixel of an encoding's image (0 for JPEG, whose size varies).
int bytes_per_pixel(Encoding e);

// One encoding of a frame; quality only for JPEG (1-100), 0 otherwise.
struct EncodingKey {
  Encoding encoding = Encoding::kRgb;
  int quality = 0;
  bool operator==(const EncodingKey& o) const { return encoding == o.encoding && quality == o.quality; }
};

// An all-black image of that size in that encoding (a camera-blackout fault's frames): depth all NaN,
// segmentation all 0. Thread-safe.
std::shared_ptr<const std::string> encode_black_frame(int width_px, int height_px, const EncodingKey& key);

// A camera as the frame service serves it.
struct FrameCamera {
  std::string name;
  int vehicle = -1;          // -1: a world camera
  std::string vehicle_name;  // "" for a world camera
  int width_px = 0;
  int height_px = 0;
  double fps_hz = 0.0;
  double fx_px = 0.0, fy_px = 0.0, cx_px = 0.0, cy_px = 0.0;  // OpenCV pinhole convention
  double noise_sd = 0.0;       // field conditions (CameraConfig)
  double brightness_sd = 0.0;
  double latency_s = 0.0;
  Modalities modalities;        // what the camera gives (CameraConfig::modalities)
  double depth_near_m = 0.0;    // the clip planes depth is drawn with: nothing nearer or farther is seen
  double depth_far_m = 0.0;
  double depth_noise_m = 0.0;   // depth field conditions (CameraConfig)
  double depth_dropout = 0.0;
  std::optional<double> depth_max_m;
};

// Field conditions on one depth image (metres, NaN invalid), in place, as a stereo or ToF camera has them:
// beyond depth_max_m invalid; Gaussian noise of sd depth_noise_m * z^2 (z in metres); a fraction
// depth_dropout of the valid pixels invalid. Drawn from (seed, camera, index) like apply_sensor_effects,
// in a stream of their own. Never applied to segmentation (ground truth). Thread-safe.
void apply_depth_effects(const FrameCamera& camera, uint64_t seed, int camera_index, int64_t index,
                         std::vector<float>* depth_m);

// std::clamp(std::lround(v), 0, 255) to the bit (NaN: 0), without libm's lround: per pixel and
// channel that call took as long as the noise itself, a third of a field-conditions camera's frame.
// Pure.
inline uint8_t round_to_pixel(double v) {
  v = v > 0.0 ? v : 0.0;  // NaN too
  v = v < 255.0 ? v : 255.0;
  // truncation, then the fraction v - i (exact below 256) rounds half away from zero as lround does
  const int i = static_cast<int>(v);
  return static_cast<uint8_t>(i + (v - i >= 0.5 ? 1 : 0));
}

// Field conditions on one RGB8 or grey image, in place: a per-frame gain 1 + brightness_sd * n0 and
// per pixel and channel noise noise_sd * n, both drawn from (seed, camera, index) so a frame's
// pixels do not depend on thread timing. n is approximately Gaussian (a centred sum of four
// uniforms, unit variance): a 384 x 216 frame takes about 1.5 ms on the 2-core machine, not the
// tens that std::normal_distribution would.
void apply_sensor_effects(double noise_sd, double brightness_sd, uint64_t seed, int camera, int64_t index,
                          std::vector<uint8_t>* pixels);

// A rendered frame as consumers receive it (render thread).
struct ReadyFrame {
  int camera = -1;        // index into FrameService::cameras()
  int64_t index = 0;      // frame k of the camera (due at k / fps)
  int64_t stamp_us = 0;   // sim time of the pose shown, round(t * 1e6)
  double stamp_s = 0.0;   // the same sim time, seconds
  const FrameCamera* info = nullptr;
  Eigen::Vector3d position_enu_m = Eigen::Vector3d::Zero();  // optical centre
  Eigen::Matrix3d R_enu_cam = Eigen::Matrix3d::Identity();   // OpenCV camera frame -> ENU
  std::vector<std::pair<EncodingKey, std::shared_ptr<const std::string>>> images;
  // the tracked bodies' positions at stamp_s (FrameService::set_tracked_bodies; empty if none)
  std::vector<Eigen::Vector3d> tracked_enu_m;
  // the bytes of one encoding, or null if nobody asked for it
  const std::string* image(const EncodingKey& key) const;
};

class FrameConsumer {
 public:
  virtual ~FrameConsumer() = default;
  // Loop thread, at a control step where frame `index` of `camera` is due at sim time stamp_us: append the
  // encodings wanted (none: not wanted). Set *must_deliver if the frame may not be dropped (the clock waits).
  virtual void want(int camera, int64_t index, int64_t stamp_us, std::vector<EncodingKey>* encodings,
                    bool* must_deliver) = 0;
  // Loop thread: a frame this consumer wanted was dropped before rendering (the renderer is behind).
  virtual void dropped(int camera, int64_t index) = 0;
  // Render thread: a frame this consumer wanted, with (at least) every encoding it asked for.
  virtual void deliver(const ReadyFrame& frame) = 0;
};

struct FrameServiceOptions {
  size_t queue_depth = 4;            // snapshots waiting for the renderer; beyond: frames are dropped
  uint64_t seed = 1;                 // camera noise (field conditions)
  std::string backend = "osmesa";    // make_gl_context: "osmesa", "egl" or "auto"
  int render_threads = 0;            // 0: default_render_threads(); more than the cameras: one per camera
  CameraOwners owners;               // the vehicles, for the segmentation labels (label_geoms)
};

// Render threads when none are asked for: one per two hardware threads, at most kMaxDefaultRenderThreads,
// at most one per camera, at least one. Each is a GL context with its own copy of the meshes and textures,
// and on llvmpipe each context starts its own rasteriser threads (LP_NUM_THREADS, default: one per CPU), so
// render threads overlap only the single-threaded parts of a frame (scene, vertices, read-back, encoding);
// more of them than cores only add memory and switching. Thread-safe.
inline constexpr int kMaxDefaultRenderThreads = 8;
int default_render_threads(size_t camera_count);

// Which of `threads` render threads renders each camera: in camera order, each goes to the thread with the
// least work so far (pixels x fps; ties to the lower index), so cameras of different vehicles spread over
// the threads and the split depends only on the cameras. Pure.
std::vector<int> assign_cameras(const std::vector<FrameCamera>& cameras, int threads);

struct FrameServiceStats {
  uint64_t snapshots = 0;            // control steps at which frames were taken
  uint64_t frames_rendered = 0;      // camera images rendered
  uint64_t frames_dropped = 0;       // camera frames dropped because the queue was full
};

class FrameService {
 public:
  // Starts the render threads and builds their renderers there, one at a time (CameraRenderer). Throws
  // std::invalid_argument / std::runtime_error as CameraRenderer does (e.g. no GL), from this thread, and
  // std::invalid_argument for a negative render_threads. m must outlive the service.
  FrameService(const mjModel_* m, const std::vector<CameraSetup>& cameras, const FrameServiceOptions& options = {});
  ~FrameService();  // stops the render threads; frames not yet rendered are not delivered
  FrameService(const FrameService&) = delete;
  FrameService& operator=(const FrameService&) = delete;

  // The cameras, in the world's camera order. Thread-safe (never changes).
  const std::vector<FrameCamera>& cameras() const { return cameras_; }
  // The object and class of every geom, as the segmentation images give them. Thread-safe (never changes).
  const SegmentationLabels& labels() const { return labels_; }
  std::optional<int> find(const std::string& name) const;

  // Loop thread, before capture() runs for the first time with it.
  void add_consumer(FrameConsumer* consumer);
  // Loop thread, before the first capture(): the bodies (MuJoCo body ids, e.g. the vehicles' roots) whose
  // positions every ReadyFrame carries in tracked_enu_m, and which camera directors aim at.
  void set_tracked_bodies(std::vector<int> body_ids) { tracked_bodies_ = std::move(body_ids); }
  // Loop thread, before the first capture(): camera `camera` (a world camera) is posed by `director` at
  // every frame from the tracked bodies' positions instead of by the model (--record-camera follow|top).
  // Its subscribers see the directed view. The director is used on the render thread only.
  void set_director(int camera, std::shared_ptr<CameraDirector> director);

  // Loop thread, at each control step before it runs: takes the frames due now. Idempotent per sim time
  // (the gate may run several times at one held step); a sim time earlier than the last one (reset)
  // restarts every camera's frame grid at k = 0.
  void capture(mjData_* d);
  // Loop thread: waits until every snapshot taken so far has been rendered and delivered (a frame with
  // latency: once sim time has reached its delivery time).
  void wait_delivered();
  // Loop thread, before a lockstep tick: waits until every frame due by the last capture's sim time
  // has been delivered: those of cameras without latency, and the held ones whose delivery time has
  // come. Unlike wait_delivered it does not wait for frames still inside their camera's latency:
  // their rendering goes on beside the clients' turns and the steps up to their delivery (60 ms
  // of latency spans one or two of a mission's 50 ms ticks). The held frames that are due are
  // delivered on this thread if the render threads are busy with later snapshots; the frames and
  // their order are the same either way.
  void wait_due();

  FrameServiceStats stats() const;

  // The GL backend and renderer, for the startup log (CameraRenderer::gl_summary). Thread-safe.
  const std::string& gl_summary() const { return gl_summary_; }
  // How many threads render (options.render_threads, or the default; at most one per camera). Thread-safe.
  int render_threads() const { return static_cast<int>(workers_.size()); }

 private:
  struct Job {
    int camera = -1;
    int64_t index = 0;
    std::vector<EncodingKey> encodings;
    std::vector<FrameConsumer*> consumers;
  };
  struct Snapshot {
    uint64_t id = 0;
    double time = 0.0;
    std::vector<double> qpos, qvel, act, mocap_pos, mocap_quat;
    std::vector<float> geom_rgba;
    std::vector<int> geom_group;
    std::vector<Job> jobs;
  };
  // a frame held back by its camera's latency
  struct Delayed {
    int64_t release_us = 0;
    ReadyFrame frame;
    std::vector<FrameConsumer*> consumers;
  };
  struct Worker;  // one render thread's renderer, model and data (frame_service.cpp)
  void start_workers(const std::vector<CameraSetup>& cameras);        // render thread
  void build_worker(int k, const std::vector<CameraSetup>& cameras);  // on worker k's thread
  void render_thread_main();
  void helper_main(int k);
  void render_snapshot(Snapshot& s);
  void render_share(int k, const Snapshot& s, std::vector<std::optional<ReadyFrame>>* out);
  bool delayed_due_locked() const;  // a held frame is due at sim_now_us_ (mutex_ held)
  void release_due();  // render thread (or wait_due): delivers the held frames that are due

  const mjModel_* m_;
  std::vector<FrameCamera> cameras_;
  SegmentationLabels labels_;
  FrameServiceOptions options_;
  std::vector<FrameConsumer*> consumers_;
  std::vector<int> tracked_bodies_;
  std::vector<std::shared_ptr<CameraDirector>> directors_;  // per camera, null: posed by the model

  // loop thread
  std::vector<int64_t> next_index_;   // per camera: the next frame index not yet taken
  std::optional<int64_t> last_capture_us_;
  uint64_t next_id_ = 1;
  bool any_latency_ = false;          // a camera holds its frames back (else capture() skips that part)

  mutable std::mutex mutex_;
  std::condition_variable cv_;
  std::deque<std::unique_ptr<Snapshot>> queue_;  // guarded by mutex_
  std::vector<std::unique_ptr<Snapshot>> spare_; // recycled snapshots, guarded by mutex_
  uint64_t done_id_ = 0;                         // last snapshot id rendered and delivered
  // (id, earliest delivery time in us) of each snapshot not yet rendered, in id order; mutex_
  std::deque<std::pair<uint64_t, int64_t>> undone_due_;
  // held by release_due: one thread at a time delivers held frames, in their order
  std::mutex release_mutex_;
  std::deque<Delayed> delayed_;                  // frames waiting out their latency, guarded by mutex_
  int64_t sim_now_us_ = 0;                       // the last capture's sim time, guarded by mutex_
  int releasing_ = 0;                            // held frames being delivered now, guarded by mutex_
  bool stop_ = false;
  FrameServiceStats stats_;
  std::string start_error_;
  std::string gl_summary_;  // written by the render thread before the constructor returns
  bool started_ = false;
  std::thread thread_;                            // the render thread: worker 0, and the helpers' owner
  std::vector<int> camera_thread_;                // per camera: the worker that renders it (assign_cameras)
  std::vector<std::unique_ptr<Worker>> workers_;  // sized before any thread starts; thread k uses worker k
};

}  // namespace uavsim::server::render
