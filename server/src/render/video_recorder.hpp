// VideoRecorder (uavsim-server --record out.mp4): a FrameService consumer that writes one camera's RGB frames
// to a video file, through an ffmpeg pipe (H.264 in MP4) or, without ffmpeg, OpenCV's VideoWriter (MPEG-4
// Part 2). The file plays at the recording fps, so it shows sim time. Writing happens on the recorder's own
// thread behind a bounded queue: a slow encoder drops frames (counted), never slows the renderer or physics.
#pragma once

#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "render/frame_service.hpp"
#include "render/overlay.hpp"

namespace uavsim::server::render {

struct RecorderStats {
  uint64_t frames_written = 0;
  uint64_t frames_dropped = 0;  // dropped by the renderer (behind) or by the recorder's own queue
};

class VideoRecorder : public FrameConsumer {
 public:
  // Records camera `camera` of `service` (its size), every `every`-th frame (fps = camera fps / every).
  // Throws std::runtime_error if no encoder can open `path`.
  // lossless: never drop a frame (the clock waits for the renderer and the encoder) -- for runs as fast as
  // possible (--rate 0), where waiting distorts nothing; otherwise frames are dropped, physics never waits.
  VideoRecorder(const FrameService& service, int camera, int every, const std::string& path, bool lossless = false);
  ~VideoRecorder() override;  // finish() if not done
  // Flushes the queued frames and closes the file. Call after the frame service stopped delivering.
  void finish();
  RecorderStats stats() const;
  // Burns an overlay into every frame: source is called on the loop thread when a frame is due (the state
  // it shows is that instant's) and the text is drawn on the render thread with the frame's pose and
  // tracked positions. Call before the first frame.
  void set_overlay(std::function<OverlayInfo()> source) { overlay_source_ = std::move(source); }
  const std::string& encoder() const { return encoder_; }  // "ffmpeg" or "opencv"

  void want(int camera, int64_t index, int64_t stamp_us, std::vector<EncodingKey>* encodings,
            bool* must_deliver) override;
  void dropped(int camera, int64_t index) override;
  void deliver(const ReadyFrame& frame) override;

 private:
  void writer_main();
  std::function<OverlayInfo()> overlay_source_;
  std::map<int64_t, OverlayInfo> overlays_;  // by frame index, guarded by mutex_
  int camera_;
  int every_;
  bool lossless_ = false;
  int width_ = 0, height_ = 0;
  std::string path_;
  std::string encoder_;
  FILE* pipe_ = nullptr;
  struct CvWriter;
  std::unique_ptr<CvWriter> cv_writer_;

  mutable std::mutex mutex_;
  std::condition_variable cv_;
  std::deque<std::shared_ptr<const std::string>> queue_;
  bool finishing_ = false;
  bool finished_ = false;
  RecorderStats stats_;
  std::thread thread_;
};

}  // namespace uavsim::server::render
