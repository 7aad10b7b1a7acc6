#include "render/video_recorder.hpp"

#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <opencv2/videoio.hpp>
#include <stdexcept>

namespace uavsim::server::render {

namespace {
constexpr size_t kQueueFrames = 16;

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
  cv::VideoWriter writer;
};

VideoRecorder::VideoRecorder(const FrameService& service, int camera, int every, const std::string& path,
                             bool lossless)
    : camera_(camera), every_(std::max(1, every)), lossless_(lossless), path_(path) {
  const FrameCamera& cam = service.cameras().at(static_cast<size_t>(camera));
  width_ = cam.width_px;
  height_ = cam.height_px;
  const double fps = cam.fps_hz / every_;
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
    if (!cv_writer_->writer.open(path_, cv::VideoWriter::fourcc('m', 'p', '4', 'v'), fps,
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
    if (finished_) return;
    finishing_ = true;
  }
  cv_.notify_all();
  if (thread_.joinable()) thread_.join();
  if (pipe_ != nullptr) {
    pclose(pipe_);
    pipe_ = nullptr;
  }
  if (cv_writer_) cv_writer_->writer.release();
  std::lock_guard<std::mutex> lock(mutex_);
  finished_ = true;
}

RecorderStats VideoRecorder::stats() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return stats_;
}

void VideoRecorder::want(int camera, int64_t index, int64_t, std::vector<EncodingKey>* encodings,
                         bool* must_deliver) {
  if (camera == camera_ && index % every_ == 0) {
    encodings->push_back({Encoding::kRgb, 0});
    if (lossless_) *must_deliver = true;
    if (overlay_source_) {
      OverlayInfo info = overlay_source_();
      std::lock_guard<std::mutex> lock(mutex_);
      overlays_[index] = std::move(info);
    }
  }
}

void VideoRecorder::dropped(int camera, int64_t index) {
  if (camera != camera_ || index % every_ != 0) return;
  std::lock_guard<std::mutex> lock(mutex_);
  ++stats_.frames_dropped;
  overlays_.erase(index);
}

void VideoRecorder::deliver(const ReadyFrame& frame) {
  if (frame.camera != camera_) return;
  for (const auto& [key, bytes] : frame.images) {
    if (key.encoding != Encoding::kRgb) continue;
    std::shared_ptr<const std::string> image = bytes;
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
    {
      std::unique_lock<std::mutex> lock(mutex_);
      if (lossless_) cv_.wait(lock, [&] { return finishing_ || queue_.size() < kQueueFrames; });
      if (finishing_ || queue_.size() >= kQueueFrames) {
        ++stats_.frames_dropped;
        return;
      }
      queue_.push_back(image);  // shared: no copy
    }
    cv_.notify_all();
    return;
  }
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
    if (pipe_ != nullptr) {
      ok = std::fwrite(frame->data(), 1, frame->size(), pipe_) == frame->size();
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
