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
#include <optional>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "render/frame_service.hpp"
#include "render/overlay.hpp"

namespace uavsim::server::render {

// The frame of a tiled recording (--record-layout tiled): the main view at (0, 0), the onboard
// cameras' tiles in a column right of it, tile i at (main_width, i * tile height) where the tile
// height is main_height / max(2, tiles) and each tile's width keeps its camera's aspect; the
// column is as wide as its widest tile. Sizes are even (H.264 in yuv420p needs that).
struct TileLayout {
  int width_px = 0, height_px = 0;  // the whole frame
  std::vector<PixelRect> tiles;     // per tile camera, in the order given
};
// tile_sizes: each tile camera's (width, height) in pixels. Thread-safe (pure).
TileLayout tile_layout(int main_width_px, int main_height_px,
                       const std::vector<std::pair<int, int>>& tile_sizes);

struct RecorderOptions {
  int every = 1;  // every every-th frame of the camera (fps = camera fps / every)
  // never drop a frame (the clock waits for the renderer and the encoder) -- for runs as fast as
  // possible (--rate 0), where waiting distorts nothing; otherwise frames are dropped, physics
  // never waits
  bool lossless = false;
  // onboard cameras (indices into FrameService::cameras(), not the recorded one) tiled beside the
  // main view, each labelled with its vehicle's name (tile_layout); their latest frame at each
  // recorded frame's instant
  std::vector<int> tiles;
  // the composed RGB8 frames go to this function (on the recorder's thread) instead of an encoder
  // (tests)
  std::function<void(const std::string& rgb, int width_px, int height_px)> sink;
  // per tile (missing: rgb): which image of its camera it shows; depth and segmentation in false colour
  // (false_colour_depth from max(near plane, 1 m) to the camera's depth_max_m, else min(far plane,
  // 100 m); false_colour_segmentation), so one camera may have several tiles
  std::vector<Encoding> tile_modalities;
  // called once, on the recorder's thread, when the encoder stops taking frames (it exited: a full
  // disk, a file it cannot write) with "PATH: why"; later frames are dropped (counted)
  std::function<void(const std::string& why)> on_write_error;
};

// A depth image (float32 metres, NaN invalid) as RGB8: log-scaled from near_m (red) to far_m (blue) on
// OpenCV's turbo colour map, black where nothing was measured. Thread-safe (pure).
void false_colour_depth(const float* depth_m, int width_px, int height_px, double near_m, double far_m,
                        uint8_t* rgb);
// A segmentation image (per pixel uint16 object id, uint16 class id) as RGB8: a colour per class (ground
// brown, vehicle red, balloon green, pole grey, truck blue, marker yellow, scenery violet), shaded per
// object so that neighbours of one class stand apart; black where nothing was hit. Thread-safe (pure).
void false_colour_segmentation(const uint8_t* segmentation, int width_px, int height_px, uint8_t* rgb);

struct RecorderStats {
  uint64_t frames_written = 0;
  uint64_t frames_dropped = 0;  // dropped by the renderer (behind) or by the recorder's own queue
  std::string write_error;      // "" while the encoder takes every frame, else the first failure
};

class VideoRecorder : public FrameConsumer {
 public:
  // Records camera `camera` of `service` (its size), every `every`-th frame (fps = camera fps / every).
  // Throws std::runtime_error if no encoder can open `path`.
  // lossless: never drop a frame (the clock waits for the renderer and the encoder) -- for runs as fast as
  // possible (--rate 0), where waiting distorts nothing; otherwise frames are dropped, physics never waits.
  VideoRecorder(const FrameService& service, int camera, int every, const std::string& path, bool lossless = false);
  // The same with tiles or a sink (RecorderOptions); path is unused with a sink.
  VideoRecorder(const FrameService& service, int camera, const std::string& path, RecorderOptions options);
  ~VideoRecorder() override;  // finish() if not done
  // Flushes the queued frames and closes the file. Call after the frame service stopped delivering.
  void finish();
  RecorderStats stats() const;
  // Burns an overlay into every frame: source is called on the loop thread when a frame is due (the state
  // it shows is that instant's) and the text is drawn on the render thread with the frame's pose and
  // tracked positions. Call before the first frame.
  void set_overlay(std::function<OverlayInfo()> source) { overlay_source_ = std::move(source); }
  const std::string& encoder() const { return encoder_; }  // "ffmpeg", "opencv" or "sink"
  int width_px() const { return width_; }    // of the frames written (tiles included)
  int height_px() const { return height_; }

  void want(int camera, int64_t index, int64_t stamp_us, std::vector<EncodingKey>* encodings,
            bool* must_deliver) override;
  void dropped(int camera, int64_t index) override;
  void deliver(const ReadyFrame& frame) override;

 private:
  struct Tile {
    int camera = -1;
    Encoding modality = Encoding::kRgb;
    double near_m = 0.0, far_m = 0.0;  // depth tiles: the colour map's range
    PixelRect rect;
    std::string label;
    int vehicle = -1;
    int64_t next_want_us = 0;
    std::string image;  // the latest frame, tile-sized and labelled; render thread only
  };
  struct Pending {
    int64_t stamp_us = 0;
    std::shared_ptr<const std::string> main;
  };
  void writer_main();
  void encoder_failed(const std::string& why);             // recorder's thread, or finish()
  void enqueue(std::shared_ptr<const std::string> image);  // render thread
  void flush_pending();                                    // render thread: composes and enqueues
  std::function<OverlayInfo()> overlay_source_;
  RecorderOptions options_;
  int main_width_ = 0, main_height_ = 0;
  int64_t period_us_ = 0;          // between recorded frames
  std::vector<Tile> tiles_;        // want() on the loop thread: next_want_us; the rest render thread
  std::optional<Pending> pending_; // a main frame waiting for the tiles of its instant (render thread)
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
