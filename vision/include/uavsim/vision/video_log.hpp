// Video log ("VLOG", seed 6.4): compressed camera frames with sim timestamps, keyframe flags,
// overlay drawings and printf-like text per frame. The image is stored without the drawings, so a
// log can be exported as plain video for offline tuning, or replayed with the drawings on top.
//
// File format (little-endian, version 2; version 1 files, without the planes, still read):
//   header: "UAVVLOG\0" (8 bytes), u32 version, u32 codec fourcc ('MJPG')
//   frame record: u32 record_bytes (what follows this field), i64 stamp_us, u8 flags (bit 0:
//   keyframe),
//     u32 image_bytes, image (a JPEG file), u32 overlay_count, overlays, u32 text_bytes, text
//     (UTF-8), then (version 2) u32 plane_count, planes
//   plane (a camera's depth or segmentation beside the image, lossless): u8 kind (1 depth: float32
//     metres, NaN invalid, stored as the float's 4 bytes in a 4-channel 8-bit PNG; 2 object ids,
//     3 class ids: 16-bit grey PNG), u32 png_bytes, png
//   overlay: u8 kind, u8 b, u8 g, u8 r, f32 thickness_px, then by kind
//     circle: f32 cx, cy, radius | line: f32 x1, y1, x2, y2 | rectangle: f32 x, y, width, height |
//     text: f32 x, y, font_scale, u32 bytes, text
// A record is complete or absent: a log cut short by a crash reads up to its last whole frame.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "uavsim/vision/result.hpp"

namespace uavsim::vision {

enum class VideoLogError {
  kOpenFailed,    // cannot create or open the file
  kWriteFailed,   // disk full, or the writer is closed
  kBadFormat,     // not a VLOG file, or an unknown version or codec
  kOutOfRange,    // frame index beyond the end
  kDecodeFailed,  // the stored image does not decode
  kExportFailed,  // cannot write the PNG files or the MP4
  kNoSuchPlane,   // a frame without the plane the export asked for (depth, object or class ids)
  kBadOption,     // an export option out of its range (fps, depth range, a raw dump of the image)
};

const char* to_string(VideoLogError error);

// One paint command, in image pixels.
struct Overlay {
  enum class Kind : uint8_t { kCircle = 1, kLine = 2, kRectangle = 3, kText = 4 };
  Kind kind = Kind::kCircle;
  cv::Scalar colour_bgr{0, 255, 0};
  float thickness_px = 1.0f;
  // circle: (cx, cy, radius, -); line: (x1, y1, x2, y2); rectangle: (x, y, width, height);
  // text: (x, y, font_scale, -) with the baseline's left end at (x, y)
  cv::Vec4f geometry_px{0, 0, 0, 0};
  std::string text;  // kText only

  static Overlay circle(cv::Point2f centre_px, float radius_px, cv::Scalar colour_bgr,
                        float thickness_px = 1.0f);
  static Overlay line(cv::Point2f from_px, cv::Point2f to_px, cv::Scalar colour_bgr,
                      float thickness_px = 1.0f);
  static Overlay rectangle(cv::Rect2f rect_px, cv::Scalar colour_bgr, float thickness_px = 1.0f);
  static Overlay label(cv::Point2f origin_px, std::string text, cv::Scalar colour_bgr,
                       float font_scale = 0.5f, float thickness_px = 1.0f);

  bool operator==(const Overlay& other) const;
};

// One frame as the caller hands it in.
struct VideoLogFrame {
  int64_t stamp_us = 0;  // sim time of the image
  cv::Mat image;         // CV_8UC1 or CV_8UC3 (BGR)
  std::vector<Overlay> overlays;
  std::string text;  // printf-like output tied to this frame
  // optional, the image's size, kept exactly: the camera's depth (CV_32FC1 metres, NaN invalid) and
  // segmentation (CV_16UC1 object and class ids), as client::CameraFrame has them
  cv::Mat depth_m;
  cv::Mat object_ids;
  cv::Mat class_ids;
};

// One frame read back.
struct VideoLogRecord {
  int64_t stamp_us = 0;
  bool keyframe = true;
  cv::Mat image;  // decoded (BGR or grey, as written)
  std::vector<Overlay> overlays;
  std::string text;
  cv::Mat depth_m;  // empty when the frame had none
  cv::Mat object_ids;
  cv::Mat class_ids;
};

struct VideoLogWriterOptions {
  int jpeg_quality = 90;
  size_t queue_capacity = 16;  // frames waiting for the encoder; more are dropped
  // Called once, on the writer's thread, when the first record cannot be written (a full disk):
  // with "PATH: strerror". The log then ends on the records written before it (no torn frame) and
  // later frames are dropped; a program says so where its user looks (the mission launchers treat
  // "the vision log stops here: ..." as a lost run record).
  std::function<void(const std::string& why)> on_write_error;
};

// Options whose on_write_error prints "PROGRAM: the vision log stops here: WHY" on stdout, the line
// the mission launchers watch for (a run whose records are being lost ends as a harness failure).
VideoLogWriterOptions write_error_said_by(const std::string& program);

// Writes a VLOG file on its own thread: submit() copies the frame into a bounded queue and returns
// at once; a worker encodes (JPEG) and writes. A full queue drops the frame and counts it, so a
// slow encoder or disk never stalls the image processing loop (seed 6.4).
class VideoLogWriter {
 public:
  // Creates (truncates) the file and starts the worker. Startup errors are values: kOpenFailed.
  static Result<std::unique_ptr<VideoLogWriter>, VideoLogError> open(
      const std::filesystem::path& path, const VideoLogWriterOptions& options = {});
  ~VideoLogWriter();  // close()s
  VideoLogWriter(const VideoLogWriter&) = delete;
  VideoLogWriter& operator=(const VideoLogWriter&) = delete;

  // Queues a copy of the frame; false if it was dropped (queue full, or closed, or a depth or id
  // plane of another type or size than the image). Never blocks on encoding or I/O. Thread-safe.
  bool submit(const VideoLogFrame& frame);

  // Writes what is queued, then stops the worker and closes the file; kWriteFailed if any write
  // failed. Idempotent. Thread-safe, but not concurrently with submit() from the same caller's
  // point of view: frames submitted after close() are dropped.
  Status<VideoLogError> close();

  uint64_t frames_written() const;  // Thread-safe.
  uint64_t frames_dropped() const;  // Thread-safe.
  // "" until a record could not be written, then "PATH: strerror". Thread-safe.
  std::string write_error() const;

 private:
  struct Impl;
  explicit VideoLogWriter(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

// Random access to a VLOG file: open() indexes the records; read() decodes one. Not thread-safe.
class VideoLogReader {
 public:
  static Result<std::unique_ptr<VideoLogReader>, VideoLogError> open(
      const std::filesystem::path& path);
  ~VideoLogReader();

  size_t frame_count() const;

  // The frame at an index (seed 6.4's player seeks by index; every MJPEG frame is a keyframe).
  Result<VideoLogRecord, VideoLogError> read(size_t index);

  // Timestamp of a frame without decoding it. Precondition: index < frame_count().
  int64_t stamp_us(size_t index) const;

  // Index of the last frame with stamp_us <= the given time (frame 0 if none).
  size_t index_at(int64_t stamp_us) const;

 private:
  struct Impl;
  explicit VideoLogReader(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

// Paints overlays on an image (BGR; a grey image is converted). Thread-safe.
void draw_overlays(const std::vector<Overlay>& overlays, cv::Mat* image_bgr);

// Paints a frame's text block in the top-left corner, one line per '\n'. Thread-safe.
void draw_text_block(const std::string& text, cv::Mat* image_bgr);

// Which image of each frame an export shows.
enum class VideoLogPlane {
  kImage,      // the camera image (JPEG-decoded)
  kDepth,      // the depth plane, in false colour (false_colour_depth)
  kObjectIds,  // the object-id plane, a colour per id (false_colour_ids)
  kClassIds,   // the class-id plane, a colour per id (false_colour_ids)
};

// The plane's name in options and file names: "image", "depth", "objects", "classes".
const char* to_string(VideoLogPlane plane);

struct VideoLogExportOptions {
  std::filesystem::path png_dir;  // if set: frame_000000.png, ...
  std::filesystem::path
      mp4_path;  // if set: an MP4 (OpenCV mp4v; ffmpeg through a pipe as fallback)
  bool draw_overlays = true;
  bool draw_text = true;
  double fps = 0.0;  // 0: from the timestamps (median frame interval); else (0, kMaxExportFps]
  VideoLogPlane plane = VideoLogPlane::kImage;  // what the PNGs and the MP4 show
  // the depth false colour's range, metres: 0 < near < far <= kMaxExportDepthM; what is nearer is
  // drawn as near, what is farther as far
  double depth_near_m = 1.0;
  double depth_far_m = 100.0;
  // if set (depth or id planes only): each frame's plane exactly as logged, for analysis:
  // PLANE_000000.npy (NumPy .npy, v1.0: float32 '<f4' metres with NaN for depth, uint16 '<u2' for
  // ids; shape (height, width), row-major)
  std::filesystem::path raw_dir;
};

constexpr double kMaxExportFps = 1000.0;
constexpr double kMaxExportDepthM = 1e6;

// The player/exporter (seed 6.4 "VLOG Player"): decodes every frame, optionally paints overlays and
// text on the plane's picture, writes PNGs and/or an MP4, and the raw plane. Returns the number of
// frames exported. kBadOption before anything is written for options out of range; kNoSuchPlane
// when a frame lacks the plane (checked on frame 0 before anything is written: a log of colour
// only).
Result<size_t, VideoLogError> export_video_log(const std::filesystem::path& vlog_path,
                                               const VideoLogExportOptions& options);

// A depth plane (CV_32FC1 metres, NaN: nothing measured) in false colour, CV_8UC3 BGR: the level
// 255 (1 - log(z / near) / log(far / near)), z clamped to [near, far], through OpenCV's turbo map
// (near dark red, far dark blue; log so that near detail keeps its contrast, as the server's
// --record-tile depth tiles), black where NaN. Preconditions: 0 < near_m < far_m. Thread-safe.
cv::Mat false_colour_depth(const cv::Mat& depth_m, double near_m, double far_m);

// The colour of an id in the id planes' false colour (BGR): black for 0 (nothing hit); else hue
// (id x 137.508 deg) mod 360 (the golden angle: consecutive ids far apart on the colour wheel),
// saturation 0.85, value 1.0 for odd and 0.7 for even ids. The same id has the same colour in every
// frame, log and run. Thread-safe.
cv::Vec3b id_colour_bgr(uint16_t id);

// An id plane (CV_16UC1 object or class ids) in false colour, CV_8UC3 BGR (id_colour_bgr).
// Thread-safe.
cv::Mat false_colour_ids(const cv::Mat& ids);

// Writes a CV_32FC1 or CV_16UC1 Mat as a NumPy .npy file (format 1.0, little-endian, C order);
// false if it cannot be written or is of another type. Thread-safe.
bool write_npy(const std::filesystem::path& path, const cv::Mat& plane);

}  // namespace uavsim::vision
