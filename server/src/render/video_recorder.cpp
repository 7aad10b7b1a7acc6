#include "render/video_recorder.hpp"

#include <sys/wait.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <stdexcept>

#include "uavsim/media/media_io.hpp"

namespace uavsim::server::render {

namespace {
constexpr size_t kQueueFrames = 16;
// a tile's frames are wanted a recorded frame's period apart, less this: the frames fall on
// control steps, so their spacing jitters by less than a step
constexpr int64_t kTileSlackUs = 1000;
// a depth tile's colour map ends here when the camera has no range of its own (the far plane is often
// kilometres away: everything near would be one colour)
constexpr double kDepthTileFarM = 100.0;
// and starts here at the nearest (the near plane is centimetres away: a log scale from there spends half
// its colours on the first metre)
constexpr double kDepthTileNearM = 1.0;

std::string shell_quote(const std::string& s) {
  std::string out = "'";
  for (char c : s) {
    if (c == '\'') {
      out += "'\\''";
    } else {
      out += c;
    }
  }
  return out + "'";
}
}  // namespace

struct VideoRecorder::CvWriter {
  media::VideoFileWriter writer;
};

TileLayout tile_layout(int main_width_px, int main_height_px,
                       const std::vector<std::pair<int, int>>& tile_sizes) {
  TileLayout layout;
  layout.width_px = main_width_px;
  layout.height_px = main_height_px;
  if (tile_sizes.empty()) return layout;
  const int slots = std::max<int>(2, static_cast<int>(tile_sizes.size()));
  const int tile_h = std::max(2, (main_height_px / slots) & ~1);
  int column_w = 0;
  for (size_t i = 0; i < tile_sizes.size(); ++i) {
    const auto [w, h] = tile_sizes[i];
    const double aspect = h > 0 ? static_cast<double>(w) / h : 4.0 / 3.0;
    const int tile_w = std::max(2, static_cast<int>(std::lround(tile_h * aspect)) & ~1);
    layout.tiles.push_back({main_width_px, static_cast<int>(i) * tile_h, tile_w, tile_h});
    column_w = std::max(column_w, tile_w);
  }
  layout.width_px = main_width_px + column_w;
  return layout;
}

void false_colour_depth(const float* depth_m, int width_px, int height_px, double near_m, double far_m,
                        uint8_t* rgb) {
  // log(z / near) / log(far / near) in [0, 1] => 255 (near) .. 0 (far) on turbo: near red, far blue
  const double lo = std::max(near_m, 1e-3);
  const double span = std::log(std::max(far_m, lo * 1.001) / lo);
  const size_t pixels = static_cast<size_t>(width_px) * height_px;
  cv::Mat level(height_px, width_px, CV_8UC1);
  cv::Mat valid(height_px, width_px, CV_8UC1);
  for (size_t i = 0; i < pixels; ++i) {
    const float z = depth_m[i];
    valid.data[i] = std::isfinite(z) ? 255 : 0;
    const double t = std::isfinite(z) ? std::clamp(std::log(std::max<double>(z, lo) / lo) / span, 0.0, 1.0) : 1.0;
    level.data[i] = static_cast<uint8_t>(std::lround(255.0 * (1.0 - t)));
  }
  cv::Mat bgr;
  cv::applyColorMap(level, bgr, cv::COLORMAP_TURBO);
  cv::Mat out(height_px, width_px, CV_8UC3, rgb);
  out.setTo(cv::Scalar::all(0));
  cv::Mat colour;
  cv::cvtColor(bgr, colour, cv::COLOR_BGR2RGB);
  colour.copyTo(out, valid);
}

void false_colour_segmentation(const uint8_t* segmentation, int width_px, int height_px, uint8_t* rgb) {
  // by class id (segmentation.hpp): none, ground, vehicle, balloon, pole, truck, marker, scenery
  static constexpr uint8_t kClassRgb[kSegmentClassCount][3] = {
      {0, 0, 0},     {150, 110, 60}, {230, 40, 40},  {40, 220, 60},
      {170, 170, 170}, {50, 90, 230}, {250, 230, 40}, {160, 80, 200}};
  const size_t pixels = static_cast<size_t>(width_px) * height_px;
  for (size_t i = 0; i < pixels; ++i, segmentation += 4, rgb += 3) {
    const unsigned object = segmentation[0] | (segmentation[1] << 8);
    const unsigned cls = segmentation[2] | (segmentation[3] << 8);
    const uint8_t* c = kClassRgb[cls < static_cast<unsigned>(kSegmentClassCount) ? cls : 0];
    // objects of one class: 60 % to 100 % of its colour, by id
    const unsigned shade = 60 + (object * 37u) % 41u;
    for (int k = 0; k < 3; ++k) rgb[k] = static_cast<uint8_t>(c[k] * shade / 100u);
  }
}

VideoRecorder::VideoRecorder(const FrameService& service, int camera, int every,
                             const std::string& path, bool lossless)
    : VideoRecorder(service, camera, path,
                    RecorderOptions{every, lossless, {}, nullptr, {}, nullptr}) {}

VideoRecorder::VideoRecorder(const FrameService& service, int camera, const std::string& path,
                             RecorderOptions options)
    : options_(std::move(options)), camera_(camera), every_(std::max(1, options_.every)),
      lossless_(options_.lossless), path_(path) {
  const FrameCamera& cam = service.cameras().at(static_cast<size_t>(camera));
  main_width_ = cam.width_px;
  main_height_ = cam.height_px;
  const double fps = cam.fps_hz / every_;
  period_us_ = std::llround(1e6 / fps);
  // the tiles: a column beside the main view
  std::vector<std::pair<int, int>> sizes;
  for (size_t i = 0; i < options_.tiles.size(); ++i) {
    const int t = options_.tiles[i];
    const FrameCamera& c = service.cameras().at(static_cast<size_t>(t));
    if (t == camera) throw std::invalid_argument("--record-layout: the recorded camera cannot be a tile");
    const Encoding e = i < options_.tile_modalities.size() ? options_.tile_modalities[i] : Encoding::kRgb;
    const bool given = e == Encoding::kDepth          ? c.modalities.depth
                       : e == Encoding::kSegmentation ? c.modalities.segmentation
                       : e == Encoding::kRgb          ? c.modalities.rgb
                                                      : false;
    if (!given) {
      throw std::invalid_argument("--record-tile " + c.name + ":" + encoding_name(e) + ": the camera gives no " +
                                  encoding_name(e) + " (a tile shows rgb, depth or segmentation)");
    }
    sizes.emplace_back(c.width_px, c.height_px);
  }
  const TileLayout layout = tile_layout(main_width_, main_height_, sizes);
  width_ = layout.width_px;
  height_ = layout.height_px;
  for (size_t i = 0; i < options_.tiles.size(); ++i) {
    const FrameCamera& c = service.cameras()[static_cast<size_t>(options_.tiles[i])];
    Tile tile;
    tile.camera = options_.tiles[i];
    tile.modality = i < options_.tile_modalities.size() ? options_.tile_modalities[i] : Encoding::kRgb;
    tile.near_m = std::max(c.depth_near_m, kDepthTileNearM);
    tile.far_m = c.depth_max_m.value_or(std::min(c.depth_far_m, kDepthTileFarM));
    tile.rect = layout.tiles[i];
    tile.vehicle = c.vehicle;
    tile.label = c.vehicle_name.empty() ? c.name : c.vehicle_name + " " + c.name;
    if (tile.modality != Encoding::kRgb) tile.label += std::string(" ") + encoding_name(tile.modality);
    // no frame yet: dark grey, labelled
    tile.image.assign(static_cast<size_t>(tile.rect.width_px) * tile.rect.height_px * 3, 40);
    draw_tile_label(tile.label, tile.vehicle, tile.rect.width_px, tile.rect.height_px,
                    reinterpret_cast<uint8_t*>(tile.image.data()));
    tiles_.push_back(std::move(tile));
  }
  if (options_.sink) {
    encoder_ = "sink";
    thread_ = std::thread([this] { writer_main(); });
    return;
  }
  std::signal(SIGPIPE, SIG_IGN);  // an encoder that exits early must not kill the server
  if (std::system("command -v ffmpeg >/dev/null 2>&1") == 0) {
    char size[32];
    std::snprintf(size, sizeof(size), "%dx%d", width_, height_);
    const std::string cmd = "ffmpeg -loglevel error -y -f rawvideo -pix_fmt rgb24 -s " + std::string(size) +
                            " -r " + std::to_string(fps) + " -i - -an -c:v libx264 -preset veryfast -pix_fmt yuv420p " +
                            shell_quote(path_);
    pipe_ = popen(cmd.c_str(), "w");
    if (pipe_ != nullptr) encoder_ = "ffmpeg";
  }
  if (pipe_ == nullptr) {
    cv_writer_ = std::make_unique<CvWriter>();
    if (!cv_writer_->writer.open(path_, media::fourcc('m', 'p', '4', 'v'), fps,
                                 cv::Size(width_, height_))) {
      throw std::runtime_error("--record: cannot open a video encoder for " + path_);
    }
    encoder_ = "opencv";
  }
  thread_ = std::thread([this] { writer_main(); });
}

VideoRecorder::~VideoRecorder() { finish(); }

void VideoRecorder::finish() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (finished_ || finishing_) return;
  }
  flush_pending();  // the frame service has stopped delivering: the last main frame goes as it is
  {
    std::lock_guard<std::mutex> lock(mutex_);
    finishing_ = true;
  }
  cv_.notify_all();
  if (thread_.joinable()) thread_.join();
  if (pipe_ != nullptr) {
    // the encoder's own end: one that fails writing the file's tail (a full disk) exits non-zero
    const int status = pclose(pipe_);
    pipe_ = nullptr;
    if (status != 0) {
      encoder_failed(path_ + ": the encoder (ffmpeg) " +
                     (WIFEXITED(status) ? "exited with code " + std::to_string(WEXITSTATUS(status))
                                        : std::string("ended abnormally")));
    }
  }
  if (cv_writer_) cv_writer_->writer.release();
  // an encoder that could write the frames but not the file's index (MP4 keeps it at the end: a
  // disk that fills then) may still exit 0, leaving a file no player opens
  const RecorderStats so_far = stats();
  if (!options_.sink && so_far.frames_written > 0 && so_far.write_error.empty() &&
      !media::ffmpeg_can_open(path_)) {
    encoder_failed(path_ +
                   ": the finished video cannot be opened (the encoder could not complete it)");
  }
  std::lock_guard<std::mutex> lock(mutex_);
  finished_ = true;
}

void VideoRecorder::encoder_failed(const std::string& why) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!stats_.write_error.empty()) return;
    stats_.write_error = why;
  }
  if (options_.on_write_error) options_.on_write_error(why);
}

RecorderStats VideoRecorder::stats() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return stats_;
}

void VideoRecorder::want(int camera, int64_t index, int64_t stamp_us, std::vector<EncodingKey>* encodings,
                         bool* must_deliver) {
  if (camera == camera_ && index % every_ == 0) {
    encodings->push_back({Encoding::kRgb, 0});
    if (lossless_) *must_deliver = true;
    if (overlay_source_) {
      OverlayInfo info = overlay_source_();
      std::lock_guard<std::mutex> lock(mutex_);
      overlays_[index] = std::move(info);
    }
    return;
  }
  // a tile's camera: a frame per recorded frame's period at most (a reset starts again), with the image
  // of each of its tiles
  for (Tile& tile : tiles_) {
    if (tile.camera != camera) continue;
    if (stamp_us + period_us_ < tile.next_want_us) tile.next_want_us = 0;
    if (stamp_us < tile.next_want_us) continue;
    tile.next_want_us = stamp_us + period_us_ - kTileSlackUs;
    encodings->push_back({tile.modality, 0});
    if (lossless_) *must_deliver = true;
  }
}

void VideoRecorder::dropped(int camera, int64_t index) {
  if (camera != camera_ || index % every_ != 0) return;
  std::lock_guard<std::mutex> lock(mutex_);
  ++stats_.frames_dropped;
  overlays_.erase(index);
}

void VideoRecorder::deliver(const ReadyFrame& frame) {
  // a main frame waits for the tiles of its instant, which come after it in the same snapshot; a
  // frame of another instant means they all came
  if (pending_ && (frame.camera == camera_ || frame.stamp_us != pending_->stamp_us)) flush_pending();
  bool tiled = false;
  for (Tile& tile : tiles_) {
    if (tile.camera != frame.camera) continue;
    tiled = true;
    const std::string* bytes = frame.image({tile.modality, 0});
    if (bytes == nullptr || frame.info == nullptr) continue;
    const int w = frame.info->width_px, h = frame.info->height_px;
    cv::Mat src(h, w, CV_8UC3, const_cast<char*>(bytes->data()));
    if (tile.modality == Encoding::kDepth) {
      src = cv::Mat(h, w, CV_8UC3);
      false_colour_depth(reinterpret_cast<const float*>(bytes->data()), w, h, tile.near_m, tile.far_m, src.data);
    } else if (tile.modality == Encoding::kSegmentation) {
      src = cv::Mat(h, w, CV_8UC3);
      false_colour_segmentation(reinterpret_cast<const uint8_t*>(bytes->data()), w, h, src.data);
    }
    // labels stay sharp when shrunk: nearest neighbour, not an average of ids and depths
    const int interpolation = tile.modality == Encoding::kRgb ? cv::INTER_AREA : cv::INTER_NEAREST;
    cv::Mat dst(tile.rect.height_px, tile.rect.width_px, CV_8UC3, tile.image.data());
    cv::resize(src, dst, dst.size(), 0, 0, interpolation);
    draw_tile_label(tile.label, tile.vehicle, tile.rect.width_px, tile.rect.height_px,
                    reinterpret_cast<uint8_t*>(tile.image.data()));
  }
  if (tiled || frame.camera != camera_) return;
  const std::string* bytes = frame.image({Encoding::kRgb, 0});
  if (bytes == nullptr) return;
  std::shared_ptr<const std::string> image;
  if (overlay_source_) {
    // the overlay on a copy: other subscribers of this camera get the plain frame
    std::optional<OverlayInfo> info;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      auto it = overlays_.find(frame.index);
      if (it != overlays_.end()) info = std::move(it->second);
      overlays_.erase(overlays_.begin(), overlays_.upper_bound(frame.index));  // this one and older
    }
    if (info && frame.info != nullptr) {
      auto drawn = std::make_shared<std::string>(*bytes);
      draw_overlay(*info, *frame.info, frame.position_enu_m, frame.R_enu_cam, frame.tracked_enu_m,
                   reinterpret_cast<uint8_t*>(drawn->data()));
      image = std::move(drawn);
    }
  }
  if (!image) {
    for (const auto& [key, b] : frame.images) {
      if (key.encoding == Encoding::kRgb) image = b;  // shared: no copy
    }
  }
  if (tiles_.empty()) {
    enqueue(std::move(image));
  } else {
    pending_ = Pending{frame.stamp_us, std::move(image)};
  }
}

void VideoRecorder::flush_pending() {
  if (!pending_) return;
  Pending p = std::move(*pending_);
  pending_.reset();
  // the main view left, the tiles in a column right of it, black around them
  auto out = std::make_shared<std::string>(static_cast<size_t>(width_) * height_ * 3, '\0');
  const size_t main_row = static_cast<size_t>(main_width_) * 3;
  for (int y = 0; y < main_height_ && y < height_; ++y) {
    std::memcpy(out->data() + static_cast<size_t>(y) * width_ * 3, p.main->data() + y * main_row, main_row);
  }
  for (const Tile& tile : tiles_) {
    const size_t row = static_cast<size_t>(tile.rect.width_px) * 3;
    for (int y = 0; y < tile.rect.height_px && tile.rect.y_px + y < height_; ++y) {
      std::memcpy(out->data() + (static_cast<size_t>(tile.rect.y_px + y) * width_ + tile.rect.x_px) * 3,
                  tile.image.data() + y * row, row);
    }
  }
  enqueue(std::move(out));
}

void VideoRecorder::enqueue(std::shared_ptr<const std::string> image) {
  {
    std::unique_lock<std::mutex> lock(mutex_);
    if (lossless_) cv_.wait(lock, [&] { return finishing_ || queue_.size() < kQueueFrames; });
    if (finishing_ || queue_.size() >= kQueueFrames) {
      ++stats_.frames_dropped;
      return;
    }
    queue_.push_back(std::move(image));
  }
  cv_.notify_all();
}

void VideoRecorder::writer_main() {
  for (;;) {
    std::shared_ptr<const std::string> frame;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      cv_.wait(lock, [&] { return finishing_ || !queue_.empty(); });
      if (queue_.empty()) return;  // finishing and drained
      frame = queue_.front();
      queue_.pop_front();
    }
    cv_.notify_all();  // room for a lossless deliver
    bool ok = true;
    bool encoder_dead = false;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      encoder_dead = !stats_.write_error.empty();
    }
    if (encoder_dead) {
      ok = false;  // a dead encoder's pipe would refuse each frame again
    } else if (options_.sink) {
      options_.sink(*frame, width_, height_);
    } else if (pipe_ != nullptr) {
      ok = std::fwrite(frame->data(), 1, frame->size(), pipe_) == frame->size();
      if (!ok) {
        const int err = errno;
        encoder_failed(path_ + ": the encoder (ffmpeg) stopped taking frames after " +
                       std::to_string(stats().frames_written) + ": " + std::strerror(err));
      }
    } else {
      const cv::Mat rgb(height_, width_, CV_8UC3, const_cast<char*>(frame->data()));
      cv::Mat bgr;
      cv::cvtColor(rgb, bgr, cv::COLOR_RGB2BGR);
      cv_writer_->writer.write(bgr);
    }
    std::lock_guard<std::mutex> lock(mutex_);
    if (ok) {
      ++stats_.frames_written;
    } else {
      ++stats_.frames_dropped;
    }
  }
}

}  // namespace uavsim::server::render
