#include "render/frame_service.hpp"

#include <mujoco/mujoco.h>

#include <algorithm>
#include <cmath>
#include <future>
#include <limits>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

#include "render/camera_director.hpp"
#include "render/camera_renderer.hpp"
#include "render/camera_setup.hpp"
#include "uavsim/common/splitmix.hpp"
#include "uavsim/media/media_io.hpp"

namespace uavsim::server::render {

namespace {

// BT.601 luma in 16-bit fixed point, as CameraRenderer's grey images
constexpr uint32_t kLumaR = 19595, kLumaG = 38470, kLumaB = 7471;

std::shared_ptr<const std::string> encode(const std::vector<uint8_t>& rgb, int w, int h, const EncodingKey& key) {
  auto out = std::make_shared<std::string>();
  switch (key.encoding) {
    case Encoding::kRgb:
      out->assign(reinterpret_cast<const char*>(rgb.data()), rgb.size());
      break;
    case Encoding::kGrey: {
      out->resize(static_cast<size_t>(w) * h);
      const uint8_t* src = rgb.data();
      for (size_t i = 0; i < out->size(); ++i, src += 3) {
        (*out)[i] = static_cast<char>((kLumaR * src[0] + kLumaG * src[1] + kLumaB * src[2] + 32768) >> 16);
      }
      break;
    }
    case Encoding::kJpeg: {
      const cv::Mat view(h, w, CV_8UC3, const_cast<uint8_t*>(rgb.data()));
      cv::Mat bgr;
      cv::cvtColor(view, bgr, cv::COLOR_RGB2BGR);
      std::vector<uint8_t> buf;
      media::encode_image(".jpg", bgr, &buf,
                          {cv::IMWRITE_JPEG_QUALITY, std::clamp(key.quality, 1, 100)});
      out->assign(reinterpret_cast<const char*>(buf.data()), buf.size());
      break;
    }
    case Encoding::kDepth:
    case Encoding::kSegmentation:
      break;  // not of the colour image: encode_depth, encode_segmentation
  }
  return out;
}

// float32 metres as they lie in memory: little-endian on every platform the server builds for
std::shared_ptr<const std::string> encode_depth(const std::vector<float>& depth_m) {
  static_assert(sizeof(float) == 4, "depth is float32");
  return std::make_shared<std::string>(reinterpret_cast<const char*>(depth_m.data()), depth_m.size() * sizeof(float));
}

// per pixel: uint16 object id, uint16 class id (little-endian); a geom id outside the labels is nothing
std::shared_ptr<const std::string> encode_segmentation(const std::vector<int32_t>& geom_ids,
                                                       const SegmentationLabels& labels) {
  auto out = std::make_shared<std::string>(geom_ids.size() * 4, '\0');
  auto* dst = reinterpret_cast<uint8_t*>(out->data());
  const auto ngeom = static_cast<int32_t>(labels.geom_object.size());
  for (const int32_t g : geom_ids) {
    const bool known = g >= 0 && g < ngeom;
    const uint16_t object = known ? labels.geom_object[static_cast<size_t>(g)] : 0;
    const auto cls = known ? static_cast<uint16_t>(labels.geom_class[static_cast<size_t>(g)]) : uint16_t{0};
    dst[0] = static_cast<uint8_t>(object & 0xFF);
    dst[1] = static_cast<uint8_t>(object >> 8);
    dst[2] = static_cast<uint8_t>(cls & 0xFF);
    dst[3] = static_cast<uint8_t>(cls >> 8);
    dst += 4;
  }
  return out;
}

// The noise of one frame: splitmix64 seeded from (seed, stream, camera, index), so a frame's noise does not
// depend on thread timing; each kind of effect draws from a stream of its own.
class FrameNoise {
 public:
  FrameNoise(uint64_t seed, uint64_t stream, int camera, int64_t index)
      : state_(seed ^ (stream + static_cast<uint64_t>(camera) * common::kSplitMixGamma) ^
               (static_cast<uint64_t>(index) * 0xBF58476D1CE4E5B9ull)) {}
  uint64_t next() { return common::splitmix64_mix(state_ += common::kSplitMixGamma); }
  // approximately N(0, 1): the centred sum of four 16-bit uniforms (mean 2, variance 4/12), scaled
  double gauss() {
    constexpr double kScale = 1.7320508075688772 / 65536.0;  // sqrt(3) per 16-bit unit
    const uint64_t r = next();
    // at most 18 bits: through int64, whose conversion is one instruction (uint64 takes a branch)
    const double sum = static_cast<double>(static_cast<int64_t>(
        (r & 0xFFFF) + ((r >> 16) & 0xFFFF) + ((r >> 32) & 0xFFFF) + (r >> 48)));
    return sum * kScale - 2.0 * 65536.0 * kScale;
  }
  // uniform in [0, 1)
  double uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }

 private:
  uint64_t state_;
};

constexpr uint64_t kColourStream = 0xCA3E7A00ull;
constexpr uint64_t kDepthStream = 0xDE9750000ull;

// When a frame exposed at sim time time_s reaches its consumers (us): once sim time reaches
// exposure + latency. One rule for a held frame's release and for the tick's wait (wait_due),
// which must agree to the microsecond.
int64_t delivery_us(double time_s, double latency_s) {
  return std::llround((time_s + latency_s) * 1e6);
}

}  // namespace

std::shared_ptr<const std::string> encode_black_frame(int width_px, int height_px, const EncodingKey& key) {
  const size_t pixels = static_cast<size_t>(width_px) * height_px;
  if (key.encoding == Encoding::kDepth) {
    return encode_depth(std::vector<float>(pixels, std::numeric_limits<float>::quiet_NaN()));
  }
  if (key.encoding == Encoding::kSegmentation) return std::make_shared<std::string>(pixels * 4, '\0');
  const std::vector<uint8_t> black(pixels * 3, 0);
  return encode(black, width_px, height_px, key);
}

const char* encoding_name(Encoding e) {
  switch (e) {
    case Encoding::kRgb: return "rgb";
    case Encoding::kGrey: return "grey";
    case Encoding::kJpeg: return "jpeg";
    case Encoding::kDepth: return "depth";
    case Encoding::kSegmentation: return "segmentation";
  }
  return "?";
}

bool is_colour(Encoding e) { return e == Encoding::kRgb || e == Encoding::kGrey || e == Encoding::kJpeg; }

bool gives(const Modalities& m, Encoding e) {
  switch (e) {
    case Encoding::kGrey:
      return m.grey;
    case Encoding::kDepth:
      return m.depth;
    case Encoding::kSegmentation:
      return m.segmentation;
    case Encoding::kRgb:
    case Encoding::kJpeg:
      return m.rgb;
  }
  return false;
}

int bytes_per_pixel(Encoding e) {
  switch (e) {
    case Encoding::kRgb: return 3;
    case Encoding::kGrey: return 1;
    case Encoding::kJpeg: return 0;
    case Encoding::kDepth: return 4;
    case Encoding::kSegmentation: return 4;
  }
  return 0;
}

std::optional<Encoding> encoding_from_name(const std::string& name) {
  if (name == "rgb") return Encoding::kRgb;
  if (name == "grey") return Encoding::kGrey;
  if (name == "jpeg") return Encoding::kJpeg;
  if (name == "depth") return Encoding::kDepth;
  if (name == "segmentation") return Encoding::kSegmentation;
  return std::nullopt;
}

const std::string* ReadyFrame::image(const EncodingKey& key) const {
  for (const auto& [k, bytes] : images) {
    if (k == key) return bytes.get();
  }
  return nullptr;
}

void apply_sensor_effects(double noise_sd, double brightness_sd, uint64_t seed, int camera, int64_t index,
                          std::vector<uint8_t>* pixels) {
  FrameNoise noise(seed, kColourStream, camera, index);
  const double gain = std::clamp(1.0 + brightness_sd * noise.gauss(), 0.2, 2.0);
  if (!(noise_sd > 0)) {  // NaN too: no noise, as before
    for (uint8_t& p : *pixels) p = round_to_pixel(p * gain);
    return;
  }
  // in blocks: the generator's draws first, then the pixels in a loop without calls or branches
  // that the compiler can vectorise (the same values as one loop doing both)
  constexpr size_t kBlock = 256;
  double draws[kBlock];
  uint8_t* p = pixels->data();
  for (size_t left = pixels->size(); left > 0;) {
    const size_t n = std::min(left, kBlock);
    for (size_t j = 0; j < n; ++j) draws[j] = noise_sd * noise.gauss();
    for (size_t j = 0; j < n; ++j) p[j] = round_to_pixel(p[j] * gain + draws[j]);
    p += n;
    left -= n;
  }
}

void apply_depth_effects(const FrameCamera& camera, uint64_t seed, int camera_index, int64_t index,
                         std::vector<float>* depth_m) {
  FrameNoise noise(seed, kDepthStream, camera_index, index);
  constexpr float kNan = std::numeric_limits<float>::quiet_NaN();
  const double max_m = camera.depth_max_m.value_or(std::numeric_limits<double>::infinity());
  for (float& z : *depth_m) {
    if (std::isnan(z)) continue;
    // out of range, then unmatched, then the measurement's noise (never closer than the near plane)
    if (z > max_m || (camera.depth_dropout > 0 && noise.uniform() < camera.depth_dropout)) {
      z = kNan;
      continue;
    }
    if (camera.depth_noise_m > 0) {
      const double noisy = z + camera.depth_noise_m * static_cast<double>(z) * z * noise.gauss();
      z = static_cast<float>(std::max(noisy, camera.depth_near_m));
    }
  }
}

int default_render_threads(size_t camera_count) {
  // one per two hardware threads: llvmpipe already rasterises each context on every core, and on the
  // 2-core development machine a second render thread gained 0-28 % and added a wake-up per snapshot
  // (docs/results/performance.md, "Cameras")
  const size_t hardware = std::max(1u, std::thread::hardware_concurrency());
  const size_t threads =
      std::min({hardware / 2, static_cast<size_t>(kMaxDefaultRenderThreads), camera_count});
  return static_cast<int>(std::max<size_t>(1, threads));
}

std::vector<int> assign_cameras(const std::vector<FrameCamera>& cameras, int threads) {
  std::vector<double> load(static_cast<size_t>(std::max(1, threads)), 0.0);
  std::vector<int> thread_of;
  for (const FrameCamera& c : cameras) {
    // min_element takes the first of equal loads: ties go to the lower index
    const auto least = std::min_element(load.begin(), load.end());
    *least += static_cast<double>(c.width_px) * c.height_px * c.fps_hz;
    thread_of.push_back(static_cast<int>(least - load.begin()));
  }
  return thread_of;
}

// One render thread's state. The renderer, model and data belong to the worker's thread (built and freed
// there); the hand-off fields pass one snapshot at a time from the render thread to a helper and back.
struct FrameService::Worker {
  mjModel* m = nullptr;
  mjData* d = nullptr;
  std::unique_ptr<CameraRenderer> renderer;
  CameraFrame frame;
  std::vector<int> renderer_index;  // per service camera: its index in this renderer; -1: another worker's

  std::mutex mutex;
  std::condition_variable cv;
  const Snapshot* snapshot = nullptr;  // work posted to a helper; null again when it is done
  std::vector<std::optional<ReadyFrame>>* out = nullptr;
  bool stop = false;
  std::thread thread;  // helpers only: worker 0 runs on the render thread

  void free_gl() {  // on the worker's thread
    renderer.reset();
    if (d) mj_deleteData(d);
    if (m) mj_deleteModel(m);
    d = nullptr;
    m = nullptr;
  }
  void stop_helper() {  // on the render thread
    {
      std::lock_guard<std::mutex> lock(mutex);
      stop = true;
    }
    cv.notify_all();
    if (thread.joinable()) thread.join();
  }
};

FrameService::FrameService(const mjModel_* m, const std::vector<CameraSetup>& cameras,
                           const FrameServiceOptions& options)
    : m_(m), labels_(label_geoms(m, options.owners)), options_(options) {
  for (const CameraSetup& c : cameras) {
    FrameCamera f;
    f.name = c.config.camera;
    f.vehicle = c.vehicle;
    f.vehicle_name = c.vehicle_name;
    f.width_px = c.config.width_px;
    f.height_px = c.config.height_px;
    f.fps_hz = c.config.fps_hz;
    f.noise_sd = c.config.noise_sd;
    f.brightness_sd = c.config.brightness_sd;
    f.latency_s = c.config.latency_s;
    f.modalities = c.config.modalities;
    f.depth_near_m = m->vis.map.znear * m->stat.extent;
    f.depth_far_m = m->vis.map.zfar * m->stat.extent;
    f.depth_noise_m = c.config.depth_noise_m;
    f.depth_dropout = c.config.depth_dropout;
    f.depth_max_m = c.config.depth_max_m;
    any_latency_ = any_latency_ || f.latency_s > 0;
    const int id = mj_name2id(m, mjOBJ_CAMERA, c.config.camera.c_str());
    if (id < 0) throw std::invalid_argument("frames: the model has no camera named '" + c.config.camera + "'");
    const CameraIntrinsics k =
        CameraIntrinsics::from_fovy_deg(f.width_px, f.height_px, c.config.fovy_deg.value_or(m->cam_fovy[id]));
    f.fx_px = k.fx_px;
    f.fy_px = k.fy_px;
    f.cx_px = k.cx_px;
    f.cy_px = k.cy_px;
    cameras_.push_back(std::move(f));
  }
  next_index_.assign(cameras_.size(), 0);
  if (options_.queue_depth == 0) options_.queue_depth = 1;

  if (options_.render_threads < 0) {
    throw std::invalid_argument("frames: render_threads must be 0 (automatic) or more, got " +
                                std::to_string(options_.render_threads));
  }
  const int threads = std::min(options_.render_threads > 0 ? options_.render_threads
                                                           : default_render_threads(cameras_.size()),
                               std::max(1, static_cast<int>(cameras_.size())));
  camera_thread_ = assign_cameras(cameras_, threads);
  for (int k = 0; k < threads; ++k) workers_.push_back(std::make_unique<Worker>());

  // the render thread builds its renderer and starts the helpers, then reports how that went
  std::promise<void> ready;
  std::future<void> started = ready.get_future();
  thread_ = std::thread([this, cameras, p = std::move(ready)]() mutable {
    try {
      start_workers(cameras);
    } catch (...) {
      p.set_exception(std::current_exception());
      return;
    }
    p.set_value();
    render_thread_main();
  });
  try {
    started.get();
  } catch (...) {
    thread_.join();
    throw;
  }
}

void FrameService::build_worker(int k, const std::vector<CameraSetup>& cameras) {
  // this worker's cameras, and a model copy whose offscreen buffer fits them
  Worker& w = *workers_[static_cast<size_t>(k)];
  std::vector<CameraConfig> configs;
  w.renderer_index.assign(cameras.size(), -1);
  for (size_t c = 0; c < cameras.size(); ++c) {
    if (camera_thread_[c] != k) continue;
    w.renderer_index[c] = static_cast<int>(configs.size());
    configs.push_back(cameras[c].config);
  }
  w.m = mj_copyModel(nullptr, m_);
  if (w.m == nullptr) throw std::runtime_error("frames: cannot copy the model");
  const OffscreenSize need = required_offscreen_size(configs);
  w.m->vis.global.offwidth = std::max(w.m->vis.global.offwidth, need.width_px);
  w.m->vis.global.offheight = std::max(w.m->vis.global.offheight, need.height_px);
  w.d = mj_makeData(w.m);
  RendererOptions ro;
  ro.backend = options_.backend;
  w.renderer = std::make_unique<CameraRenderer>(w.m, std::move(configs), ro);

  // a context's first frame with a set of effects compiles llvmpipe's shaders for it (hundreds of ms on a
  // loaded machine, per context): render one camera of each set now, before the clock starts, so that
  // real-time subscribers' first frames are not late (and dropped) while several contexts compile at once
  mj_forward(w.m, w.d);
  std::vector<RenderFlags> warmed;
  for (int i = 0; i < w.renderer->camera_count(); ++i) {
    const RenderFlags& f = w.renderer->config(i).flags;
    const bool seen = std::any_of(warmed.begin(), warmed.end(), [&f](const RenderFlags& g) {
      return g.shadows == f.shadows && g.reflections == f.reflections && g.skybox == f.skybox &&
             g.msaa_samples == f.msaa_samples;
    });
    if (seen) continue;
    w.renderer->render(w.d, i, &w.frame);
    warmed.push_back(f);
  }
  // and the depth and segmentation pass, if a camera of this worker has it
  for (int i = 0; i < w.renderer->camera_count(); ++i) {
    if (!w.renderer->config(i).modalities.geometry()) continue;
    w.renderer->render(w.d, i, RenderPasses{false, true, true}, &w.frame);
    break;
  }
}

void FrameService::start_workers(const std::vector<CameraSetup>& cameras) {
  // one at a time: MuJoCo loads its GL entry points in the first renderer, unguarded (CameraRenderer)
  try {
    build_worker(0, cameras);
    gl_summary_ = workers_[0]->renderer->gl_summary();
    for (size_t k = 1; k < workers_.size(); ++k) {
      std::promise<void> ready;
      std::future<void> built = ready.get_future();
      workers_[k]->thread = std::thread([this, k, &cameras, p = std::move(ready)]() mutable {
        try {
          build_worker(static_cast<int>(k), cameras);
        } catch (...) {
          workers_[k]->free_gl();
          p.set_exception(std::current_exception());
          return;
        }
        p.set_value();
        helper_main(static_cast<int>(k));
      });
      built.get();
    }
  } catch (...) {
    // stop the helpers started so far (a failed one has returned already), free this thread's renderer
    for (size_t k = 1; k < workers_.size(); ++k) workers_[k]->stop_helper();
    workers_[0]->free_gl();
    throw;
  }
}

FrameService::~FrameService() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  cv_.notify_all();
  if (thread_.joinable()) thread_.join();
}

std::optional<int> FrameService::find(const std::string& name) const {
  for (size_t i = 0; i < cameras_.size(); ++i) {
    if (cameras_[i].name == name) return static_cast<int>(i);
  }
  return std::nullopt;
}

void FrameService::add_consumer(FrameConsumer* consumer) { consumers_.push_back(consumer); }

FrameServiceStats FrameService::stats() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return stats_;
}

void FrameService::capture(mjData_* d) {
  const int64_t now_us = std::llround(d->time * 1e6);
  if (last_capture_us_ && now_us == *last_capture_us_) return;
  const bool back = last_capture_us_ && now_us < *last_capture_us_;
  if (back) std::fill(next_index_.begin(), next_index_.end(), 0);
  last_capture_us_ = now_us;
  if (any_latency_) {
    // frames held for their latency are released as sim time passes (a reset drops them)
    {
      std::lock_guard<std::mutex> lock(mutex_);
      sim_now_us_ = now_us;
      if (back) delayed_.clear();
    }
    cv_.notify_all();
  }

  std::vector<Job> jobs;
  bool must = false;
  for (size_t c = 0; c < cameras_.size(); ++c) {
    // frame k is due at the first control step at or after k / fps
    const double frames_now = d->time * cameras_[c].fps_hz + 1e-6;
    if (frames_now < static_cast<double>(next_index_[c])) continue;
    const int64_t k = static_cast<int64_t>(std::floor(frames_now));  // the latest due (k >= next_index_)
    next_index_[c] = k + 1;
    Job job;
    job.camera = static_cast<int>(c);
    job.index = k;
    for (FrameConsumer* consumer : consumers_) {
      std::vector<EncodingKey> wanted;
      bool consumer_must = false;
      consumer->want(job.camera, k, now_us, &wanted, &consumer_must);
      if (wanted.empty()) continue;
      job.consumers.push_back(consumer);
      must = must || consumer_must;
      for (const EncodingKey& key : wanted) {
        if (std::find(job.encodings.begin(), job.encodings.end(), key) == job.encodings.end()) {
          job.encodings.push_back(key);
        }
      }
    }
    if (!job.consumers.empty()) jobs.push_back(std::move(job));
  }
  if (jobs.empty()) return;

  std::unique_ptr<Snapshot> snap;
  {
    std::unique_lock<std::mutex> lock(mutex_);
    if (queue_.size() >= options_.queue_depth) {
      if (!must) {
        stats_.frames_dropped += jobs.size();
        lock.unlock();
        for (const Job& job : jobs) {
          for (FrameConsumer* consumer : job.consumers) consumer->dropped(job.camera, job.index);
        }
        return;
      }
      cv_.wait(lock, [&] { return queue_.size() < options_.queue_depth || stop_; });
      if (stop_) return;
    }
    if (!spare_.empty()) {
      snap = std::move(spare_.back());
      spare_.pop_back();
    }
  }
  if (!snap) snap = std::make_unique<Snapshot>();
  // the snapshot's earliest delivery: its capture time unless every camera in it has latency
  int64_t due_us = std::numeric_limits<int64_t>::max();
  for (const Job& job : jobs) {
    due_us =
        std::min(due_us, delivery_us(d->time, cameras_[static_cast<size_t>(job.camera)].latency_s));
  }
  const mjModel* m = m_;
  snap->id = next_id_++;
  snap->time = d->time;
  snap->qpos.assign(d->qpos, d->qpos + m->nq);
  snap->qvel.assign(d->qvel, d->qvel + m->nv);
  snap->act.assign(d->act, d->act + m->na);
  snap->mocap_pos.assign(d->mocap_pos, d->mocap_pos + 3 * m->nmocap);
  snap->mocap_quat.assign(d->mocap_quat, d->mocap_quat + 4 * m->nmocap);
  snap->geom_rgba.assign(m->geom_rgba, m->geom_rgba + 4 * m->ngeom);
  snap->geom_group.assign(m->geom_group, m->geom_group + m->ngeom);
  snap->jobs = std::move(jobs);
  {
    std::lock_guard<std::mutex> lock(mutex_);
    ++stats_.snapshots;
    undone_due_.emplace_back(snap->id, due_us);
    queue_.push_back(std::move(snap));
  }
  cv_.notify_all();
}

void FrameService::set_director(int camera, std::shared_ptr<CameraDirector> director) {
  directors_.resize(cameras_.size());
  directors_.at(static_cast<size_t>(camera)) = std::move(director);
}

void FrameService::wait_delivered() {
  std::unique_lock<std::mutex> lock(mutex_);
  const uint64_t target = next_id_ - 1;
  cv_.wait(lock, [&] { return (done_id_ >= target && !delayed_due_locked() && releasing_ == 0) || stop_; });
}

void FrameService::wait_due() {
  if (!any_latency_) {
    wait_delivered();  // every frame is due at its capture
    return;
  }
  {
    std::unique_lock<std::mutex> lock(mutex_);
    uint64_t target = 0;  // the last snapshot with a frame due by now (they render in id order)
    for (const auto& [id, due_us] : undone_due_) {
      if (due_us <= sim_now_us_) target = id;
    }
    cv_.wait(lock, [&] { return done_id_ >= target || stop_; });
    if (stop_) return;
  }
  // the render thread releases held frames between snapshots; it may be rendering a later one now.
  // (A release the render thread has begun ends before this one starts: release_mutex_.)
  release_due();
}

bool FrameService::delayed_due_locked() const {
  return !delayed_.empty() && delayed_.front().release_us <= sim_now_us_;
}

void FrameService::release_due() {
  std::lock_guard<std::mutex> releasing(release_mutex_);
  for (;;) {
    Delayed held;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (!delayed_due_locked()) break;
      held = std::move(delayed_.front());
      delayed_.pop_front();
      ++releasing_;  // wait_delivered waits until it has reached its consumers
    }
    for (FrameConsumer* consumer : held.consumers) consumer->deliver(held.frame);
    {
      std::lock_guard<std::mutex> lock(mutex_);
      --releasing_;
    }
  }
  cv_.notify_all();
}

void FrameService::render_thread_main() {
  for (;;) {
    std::unique_ptr<Snapshot> snap;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      cv_.wait(lock, [&] { return stop_ || !queue_.empty() || delayed_due_locked(); });
      if (stop_) break;
      if (!queue_.empty()) {
        snap = std::move(queue_.front());
        queue_.pop_front();
      }
    }
    release_due();
    if (!snap) continue;
    cv_.notify_all();  // room in the queue
    render_snapshot(*snap);
    release_due();
    {
      std::lock_guard<std::mutex> lock(mutex_);
      done_id_ = snap->id;
      while (!undone_due_.empty() && undone_due_.front().first <= done_id_) undone_due_.pop_front();
      stats_.frames_rendered += snap->jobs.size();
      snap->jobs.clear();
      if (spare_.size() < options_.queue_depth + 1) spare_.push_back(std::move(snap));
    }
    cv_.notify_all();
  }
  // the helpers free their GL resources on their threads, the render thread its own
  for (size_t k = 1; k < workers_.size(); ++k) workers_[k]->stop_helper();
  workers_[0]->free_gl();
}

void FrameService::helper_main(int k) {
  // render this worker's share of each snapshot the render thread posts, until stopped
  Worker& w = *workers_[static_cast<size_t>(k)];
  for (;;) {
    std::unique_lock<std::mutex> lock(w.mutex);
    w.cv.wait(lock, [&] { return w.stop || w.snapshot != nullptr; });
    if (w.stop) break;
    const Snapshot* snapshot = w.snapshot;
    std::vector<std::optional<ReadyFrame>>* out = w.out;
    lock.unlock();
    render_share(k, *snapshot, out);
    lock.lock();
    w.snapshot = nullptr;
    w.cv.notify_all();
  }
  w.free_gl();
}

void FrameService::render_snapshot(Snapshot& s) {
  // the workers with a camera due render their frames in parallel, each into its jobs' slots
  std::vector<std::optional<ReadyFrame>> out(s.jobs.size());
  std::vector<bool> busy(workers_.size(), false);
  for (const Job& job : s.jobs) busy[static_cast<size_t>(camera_thread_[static_cast<size_t>(job.camera)])] = true;
  for (size_t k = 1; k < workers_.size(); ++k) {
    if (!busy[k]) continue;
    Worker& w = *workers_[k];
    {
      std::lock_guard<std::mutex> lock(w.mutex);
      w.snapshot = &s;
      w.out = &out;
    }
    w.cv.notify_all();
  }
  if (busy[0]) render_share(0, s, &out);
  for (size_t k = 1; k < workers_.size(); ++k) {
    if (!busy[k]) continue;
    Worker& w = *workers_[k];
    std::unique_lock<std::mutex> lock(w.mutex);
    w.cv.wait(lock, [&] { return w.snapshot == nullptr; });
  }

  // then to the consumers in the snapshot's camera order, as one thread would have delivered them
  for (size_t i = 0; i < s.jobs.size(); ++i) {
    const Job& job = s.jobs[i];
    ReadyFrame& f = *out[i];
    const FrameCamera& cam = cameras_[static_cast<size_t>(job.camera)];
    if (cam.latency_s > 0) {
      // stamped at exposure, delivered once sim time reaches exposure + latency (release_due)
      Delayed held{delivery_us(s.time, cam.latency_s), std::move(f), job.consumers};
      std::lock_guard<std::mutex> lock(mutex_);
      const auto at = std::upper_bound(delayed_.begin(), delayed_.end(), held.release_us,
                                       [](int64_t t, const Delayed& x) { return t < x.release_us; });
      delayed_.insert(at, std::move(held));
      continue;
    }
    for (FrameConsumer* consumer : job.consumers) consumer->deliver(f);
  }
}

void FrameService::render_share(int k, const Snapshot& s, std::vector<std::optional<ReadyFrame>>* out) {
  // worker k's copy of the state at the snapshot, forwarded
  Worker& w = *workers_[static_cast<size_t>(k)];
  mjModel* m = w.m;
  mjData* d = w.d;
  d->time = s.time;
  std::copy(s.qpos.begin(), s.qpos.end(), d->qpos);
  std::copy(s.qvel.begin(), s.qvel.end(), d->qvel);
  std::copy(s.act.begin(), s.act.end(), d->act);
  std::copy(s.mocap_pos.begin(), s.mocap_pos.end(), d->mocap_pos);
  std::copy(s.mocap_quat.begin(), s.mocap_quat.end(), d->mocap_quat);
  std::copy(s.geom_rgba.begin(), s.geom_rgba.end(), m->geom_rgba);
  std::copy(s.geom_group.begin(), s.geom_group.end(), m->geom_group);
  mj_forward(m, d);
  std::vector<Eigen::Vector3d> tracked;
  for (int body : tracked_bodies_) tracked.emplace_back(Eigen::Map<const Eigen::Vector3d>(d->xpos + 3 * body));

  // this worker's cameras among the jobs: render, field conditions, encodings
  for (size_t i = 0; i < s.jobs.size(); ++i) {
    const Job& job = s.jobs[i];
    const size_t c = static_cast<size_t>(job.camera);
    if (camera_thread_[c] != k) continue;
    if (c < directors_.size() && directors_[c]) {
      // a directed camera: its pose from the director, written where mjv_updateScene reads it (cam_xmat is
      // row-major, its columns MuJoCo's camera axes: OpenCV's x, -y, -z); only this worker aims it
      const CameraPose pose = directors_[c]->aim(s.time, tracked);
      const int id = mj_name2id(m, mjOBJ_CAMERA, cameras_[c].name.c_str());
      const Eigen::Matrix3d R_enu_mjcam = pose.R_enu_cam * Eigen::Vector3d(1.0, -1.0, -1.0).asDiagonal();
      Eigen::Map<Eigen::Vector3d>(d->cam_xpos + 3 * id) = pose.position_enu_m;
      Eigen::Map<Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(d->cam_xmat + 9 * id) = R_enu_mjcam;
    }
    // the passes its encodings need: colour, and the geometry pass only for depth or segmentation
    RenderPasses passes{false, false, false};
    for (const EncodingKey& key : job.encodings) {
      passes.colour = passes.colour || is_colour(key.encoding);
      passes.depth = passes.depth || key.encoding == Encoding::kDepth;
      passes.segmentation = passes.segmentation || key.encoding == Encoding::kSegmentation;
    }
    w.renderer->render(d, w.renderer_index[c], passes, &w.frame);
    const FrameCamera& cam = cameras_[c];
    if (passes.colour && (cam.noise_sd > 0 || cam.brightness_sd > 0)) {
      apply_sensor_effects(cam.noise_sd, cam.brightness_sd, options_.seed, job.camera, job.index, &w.frame.pixels);
    }
    if (passes.depth && (cam.depth_noise_m > 0 || cam.depth_dropout > 0 || cam.depth_max_m)) {
      apply_depth_effects(cam, options_.seed, job.camera, job.index, &w.frame.depth_m);
    }
    ReadyFrame& f = (*out)[i].emplace();
    f.camera = job.camera;
    f.index = job.index;
    f.stamp_us = w.frame.stamp_us;
    f.stamp_s = s.time;
    f.info = &cam;
    f.position_enu_m = w.frame.position_enu_m;
    f.R_enu_cam = w.frame.R_enu_cam;
    f.tracked_enu_m = tracked;
    for (const EncodingKey& key : job.encodings) {
      if (key.encoding == Encoding::kDepth) {
        f.images.emplace_back(key, encode_depth(w.frame.depth_m));
      } else if (key.encoding == Encoding::kSegmentation) {
        f.images.emplace_back(key, encode_segmentation(w.frame.geom_ids, labels_));
      } else {
        f.images.emplace_back(key, encode(w.frame.pixels, w.frame.width_px, w.frame.height_px, key));
      }
    }
  }
}

}  // namespace uavsim::server::render
