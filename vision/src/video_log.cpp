#include "uavsim/vision/video_log.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <cstring>
#include <deque>
#include <fstream>
#include <functional>
#include <mutex>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <thread>

#include "uavsim/common/record_file.hpp"
#include "uavsim/media/media_io.hpp"

namespace uavsim::vision {

namespace {

constexpr char kMagic[8] = {'U', 'A', 'V', 'V', 'L', 'O', 'G', '\0'};
constexpr uint32_t kVersion = 2;  // written; 1 (no planes) is read too
constexpr uint32_t kFirstVersion = 1;
// the planes beside the image (version 2)
enum PlaneKind : uint8_t { kPlaneDepth = 1, kPlaneObjects = 2, kPlaneClasses = 3 };
constexpr uint32_t kMaxPlanes = 3;
constexpr uint32_t kFourccMjpg = 'M' | ('J' << 8) | ('P' << 16) | ('G' << 24);
constexpr size_t kHeaderBytes = 16;
constexpr uint8_t kFlagKeyframe = 1;
// a record larger than this is corruption, not a frame (a 4K BGR frame in JPEG is far below)
constexpr uint32_t kMaxRecordBytes = 256u << 20;

// --- little-endian serialisation, byte by byte so the format does not depend on the host ---
void put_u8(std::string* b, uint8_t v) { b->push_back(static_cast<char>(v)); }
void put_u32(std::string* b, uint32_t v) {
  for (int i = 0; i < 4; ++i) b->push_back(static_cast<char>((v >> (8 * i)) & 0xff));
}
void put_i64(std::string* b, int64_t v) {
  const auto u = static_cast<uint64_t>(v);
  for (int i = 0; i < 8; ++i) b->push_back(static_cast<char>((u >> (8 * i)) & 0xff));
}
void put_f32(std::string* b, float v) {
  uint32_t u;
  std::memcpy(&u, &v, 4);
  put_u32(b, u);
}
void put_bytes(std::string* b, const void* data, size_t n) {
  put_u32(b, static_cast<uint32_t>(n));
  b->append(static_cast<const char*>(data), n);
}

// Bounds-checked reader over one record; any overrun sets failed_.
class ByteReader {
 public:
  ByteReader(const uint8_t* data, size_t size) : data_(data), size_(size) {}
  bool failed() const { return failed_; }
  uint8_t u8() { return take(1) ? data_[pos_ - 1] : 0; }
  uint32_t u32() {
    if (!take(4)) return 0;
    uint32_t v = 0;
    for (int i = 0; i < 4; ++i) v |= static_cast<uint32_t>(data_[pos_ - 4 + i]) << (8 * i);
    return v;
  }
  int64_t i64() {
    if (!take(8)) return 0;
    uint64_t v = 0;
    for (int i = 0; i < 8; ++i) v |= static_cast<uint64_t>(data_[pos_ - 8 + i]) << (8 * i);
    return static_cast<int64_t>(v);
  }
  float f32() {
    const uint32_t u = u32();
    float v;
    std::memcpy(&v, &u, 4);
    return v;
  }
  // a length-prefixed byte run: pointer into the buffer and its size
  std::pair<const uint8_t*, size_t> bytes() {
    const uint32_t n = u32();
    if (failed_ || !take(n)) return {nullptr, 0};
    return {data_ + pos_ - n, n};
  }
  std::string string() {
    const auto [p, n] = bytes();
    return p ? std::string(reinterpret_cast<const char*>(p), n) : std::string();
  }

 private:
  bool take(size_t n) {
    if (failed_ || size_ - pos_ < n) {
      failed_ = true;
      return false;
    }
    pos_ += n;
    return true;
  }
  const uint8_t* data_;
  size_t size_;
  size_t pos_ = 0;
  bool failed_ = false;
};

void serialise_overlay(const Overlay& o, std::string* b) {
  put_u8(b, static_cast<uint8_t>(o.kind));
  for (int c = 0; c < 3; ++c) put_u8(b, cv::saturate_cast<uint8_t>(o.colour_bgr[c]));
  put_f32(b, o.thickness_px);
  const int n = o.kind == Overlay::Kind::kCircle || o.kind == Overlay::Kind::kText ? 3 : 4;
  for (int i = 0; i < n; ++i) put_f32(b, o.geometry_px[i]);
  if (o.kind == Overlay::Kind::kText) put_bytes(b, o.text.data(), o.text.size());
}

// a plane as a lossless PNG: depth's float bits as 4 x 8-bit channels, ids as 16-bit grey
bool serialise_plane(uint8_t kind, const cv::Mat& plane, std::string* b) {
  const cv::Mat as_png = kind == kPlaneDepth
                             ? cv::Mat(plane.rows, plane.cols, CV_8UC4, plane.data, plane.step)
                             : plane;
  std::vector<uchar> png;
  if (!media::encode_image(".png", as_png, &png)) return false;
  put_u8(b, kind);
  put_bytes(b, png.data(), png.size());
  return true;
}

bool parse_plane(ByteReader* r, VideoLogRecord* rec) {
  const uint8_t kind = r->u8();
  const auto [png, png_bytes] = r->bytes();
  if (r->failed() || kind < kPlaneDepth || kind > kPlaneClasses) return false;
  const cv::Mat decoded = media::decode_image(
      cv::Mat(1, static_cast<int>(png_bytes), CV_8UC1, const_cast<uint8_t*>(png)),
      cv::IMREAD_UNCHANGED);
  if (decoded.empty()) return false;
  if (kind == kPlaneDepth) {
    if (decoded.type() != CV_8UC4) return false;
    rec->depth_m = cv::Mat(decoded.rows, decoded.cols, CV_32FC1);
    std::memcpy(rec->depth_m.data, decoded.data, decoded.total() * 4);
    return true;
  }
  if (decoded.type() != CV_16UC1) return false;
  (kind == kPlaneObjects ? rec->object_ids : rec->class_ids) = decoded;
  return true;
}

// an optional plane: empty, or of the image's size and the type given
bool plane_fits(const cv::Mat& plane, const cv::Mat& image, int type) {
  return plane.empty() || (plane.type() == type && plane.size() == image.size());
}

bool parse_overlay(ByteReader* r, Overlay* o) {
  const uint8_t kind = r->u8();
  if (kind < 1 || kind > 4) return false;
  o->kind = static_cast<Overlay::Kind>(kind);
  const uint8_t b = r->u8(), g = r->u8(), red = r->u8();
  o->colour_bgr = cv::Scalar(b, g, red);
  o->thickness_px = r->f32();
  const int n = o->kind == Overlay::Kind::kCircle || o->kind == Overlay::Kind::kText ? 3 : 4;
  o->geometry_px = cv::Vec4f(0, 0, 0, 0);
  for (int i = 0; i < n; ++i) o->geometry_px[i] = r->f32();
  o->text.clear();
  if (o->kind == Overlay::Kind::kText) o->text = r->string();
  return !r->failed();
}

}  // namespace

const char* to_string(VideoLogError error) {
  switch (error) {
    case VideoLogError::kOpenFailed:
      return "cannot open the file";
    case VideoLogError::kWriteFailed:
      return "write failed";
    case VideoLogError::kBadFormat:
      return "not a VLOG file (or an unsupported version/codec)";
    case VideoLogError::kOutOfRange:
      return "frame index out of range";
    case VideoLogError::kDecodeFailed:
      return "image does not decode";
    case VideoLogError::kExportFailed:
      return "export failed";
    case VideoLogError::kNoSuchPlane:
      return "a frame without the plane asked for";
    case VideoLogError::kBadOption:
      return "an export option out of range";
  }
  return "unknown error";
}

const char* to_string(VideoLogPlane plane) {
  switch (plane) {
    case VideoLogPlane::kImage:
      return "image";
    case VideoLogPlane::kDepth:
      return "depth";
    case VideoLogPlane::kObjectIds:
      return "objects";
    case VideoLogPlane::kClassIds:
      return "classes";
  }
  return "unknown";
}

// --- Overlay ---

Overlay Overlay::circle(cv::Point2f centre_px, float radius_px, cv::Scalar colour_bgr,
                        float thickness_px) {
  return {Kind::kCircle, colour_bgr, thickness_px, {centre_px.x, centre_px.y, radius_px, 0}, {}};
}
Overlay Overlay::line(cv::Point2f from_px, cv::Point2f to_px, cv::Scalar colour_bgr,
                      float thickness_px) {
  return {Kind::kLine, colour_bgr, thickness_px, {from_px.x, from_px.y, to_px.x, to_px.y}, {}};
}
Overlay Overlay::rectangle(cv::Rect2f rect_px, cv::Scalar colour_bgr, float thickness_px) {
  return {Kind::kRectangle,
          colour_bgr,
          thickness_px,
          {rect_px.x, rect_px.y, rect_px.width, rect_px.height},
          {}};
}
Overlay Overlay::label(cv::Point2f origin_px, std::string text, cv::Scalar colour_bgr,
                       float font_scale, float thickness_px) {
  return {Kind::kText,
          colour_bgr,
          thickness_px,
          {origin_px.x, origin_px.y, font_scale, 0},
          std::move(text)};
}

bool Overlay::operator==(const Overlay& other) const {
  // colours are stored as bytes: compare what survives a round trip
  for (int c = 0; c < 3; ++c) {
    if (cv::saturate_cast<uint8_t>(colour_bgr[c]) !=
        cv::saturate_cast<uint8_t>(other.colour_bgr[c])) {
      return false;
    }
  }
  return kind == other.kind && thickness_px == other.thickness_px &&
         geometry_px == other.geometry_px && text == other.text;
}

// --- writer ---

struct VideoLogWriter::Impl {
  VideoLogWriterOptions options;
  // whole records with one write(2) each: a full disk or a kill leaves the log on a whole frame
  common::RecordFile file;  // the worker's, after open()
  std::mutex mutex;
  std::condition_variable cv;
  std::deque<VideoLogFrame> queue;  // guarded by mutex
  bool closing = false;             // guarded by mutex
  bool closed = false;              // guarded by mutex
  std::atomic<uint64_t> written{0};
  std::atomic<uint64_t> dropped{0};
  std::atomic<bool> write_failed{false};
  std::string write_error;  // guarded by mutex
  std::thread worker;

  // a record the file refused: the first is said once
  void refused() {
    write_failed = true;
    {
      std::lock_guard lock(mutex);
      if (!write_error.empty()) return;
      write_error = file.error();
    }
    if (options.on_write_error) options.on_write_error(file.error());
  }

  void run() {
    std::string record;
    std::vector<uchar> jpeg;
    const std::vector<int> jpeg_params = {cv::IMWRITE_JPEG_QUALITY, options.jpeg_quality};
    for (;;) {
      VideoLogFrame frame;
      {
        std::unique_lock lock(mutex);
        cv.wait(lock, [&] { return closing || !queue.empty(); });
        if (queue.empty()) return;  // closing and drained
        frame = std::move(queue.front());
        queue.pop_front();
      }
      // encode and write outside the lock: this is the slow part the caller must never wait for
      jpeg.clear();
      if (!media::encode_image(".jpg", frame.image, &jpeg, jpeg_params)) {
        write_failed = true;
        continue;
      }
      record.clear();
      put_i64(&record, frame.stamp_us);
      put_u8(&record, kFlagKeyframe);  // every MJPEG frame is a keyframe
      put_bytes(&record, jpeg.data(), jpeg.size());
      put_u32(&record, static_cast<uint32_t>(frame.overlays.size()));
      for (const auto& o : frame.overlays) serialise_overlay(o, &record);
      put_bytes(&record, frame.text.data(), frame.text.size());
      const std::pair<uint8_t, const cv::Mat*> planes[] = {{kPlaneDepth, &frame.depth_m},
                                                           {kPlaneObjects, &frame.object_ids},
                                                           {kPlaneClasses, &frame.class_ids}};
      uint32_t plane_count = 0;
      for (const auto& [kind, plane] : planes) plane_count += plane->empty() ? 0 : 1;
      put_u32(&record, plane_count);
      bool planes_ok = true;
      for (const auto& [kind, plane] : planes) {
        if (!plane->empty()) planes_ok = planes_ok && serialise_plane(kind, *plane, &record);
      }
      if (!planes_ok) {
        write_failed = true;
        continue;
      }
      // after a refusal the file refuses every later record too (RecordFile): each is dropped
      std::string framed;
      put_u32(&framed, static_cast<uint32_t>(record.size()));
      framed += record;
      if (file.write(framed)) {
        ++written;
      } else {
        ++dropped;  // this frame is not in the log
        refused();
      }
    }
  }
};

VideoLogWriterOptions write_error_said_by(const std::string& program) {
  VideoLogWriterOptions options;
  options.on_write_error = [program](const std::string& why) {
    std::printf("%s: the vision log stops here: %s\n", program.c_str(), why.c_str());
    std::fflush(stdout);
  };
  return options;
}

VideoLogWriter::VideoLogWriter(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

VideoLogWriter::~VideoLogWriter() { close(); }

Result<std::unique_ptr<VideoLogWriter>, VideoLogError> VideoLogWriter::open(
    const std::filesystem::path& path, const VideoLogWriterOptions& options) {
  auto impl = std::make_unique<Impl>();
  impl->options = options;
  impl->options.queue_capacity = std::max<size_t>(options.queue_capacity, 1);
  if (!impl->file.open(path.string(), nullptr)) return VideoLogError::kOpenFailed;
  std::string header(kMagic, sizeof(kMagic));
  put_u32(&header, kVersion);
  put_u32(&header, kFourccMjpg);
  if (!impl->file.write(header)) return VideoLogError::kOpenFailed;
  Impl* raw = impl.get();
  impl->worker = std::thread([raw] { raw->run(); });
  return std::unique_ptr<VideoLogWriter>(new VideoLogWriter(std::move(impl)));
}

bool VideoLogWriter::submit(const VideoLogFrame& frame) {
  if (frame.image.empty() || (frame.image.type() != CV_8UC3 && frame.image.type() != CV_8UC1) ||
      !plane_fits(frame.depth_m, frame.image, CV_32FC1) ||
      !plane_fits(frame.object_ids, frame.image, CV_16UC1) ||
      !plane_fits(frame.class_ids, frame.image, CV_16UC1)) {
    ++impl_->dropped;
    return false;
  }
  {
    std::lock_guard lock(impl_->mutex);
    if (impl_->closing || impl_->queue.size() >= impl_->options.queue_capacity) {
      ++impl_->dropped;
      return false;
    }
  }
  // copy outside the lock (the caller may reuse its buffer); a racing submit may fill the slot
  // meanwhile, then this one is dropped below
  VideoLogFrame copy{
      frame.stamp_us,        frame.image.clone(),      frame.overlays,         frame.text,
      frame.depth_m.clone(), frame.object_ids.clone(), frame.class_ids.clone()};
  {
    std::lock_guard lock(impl_->mutex);
    if (impl_->closing || impl_->queue.size() >= impl_->options.queue_capacity) {
      ++impl_->dropped;
      return false;
    }
    impl_->queue.push_back(std::move(copy));
  }
  impl_->cv.notify_one();
  return true;
}

Status<VideoLogError> VideoLogWriter::close() {
  {
    std::lock_guard lock(impl_->mutex);
    if (impl_->closed) {
      return impl_->write_failed ? Status<VideoLogError>(VideoLogError::kWriteFailed)
                                 : Status<VideoLogError>(std::monostate{});
    }
    impl_->closing = true;
    impl_->closed = true;
  }
  impl_->cv.notify_all();
  if (impl_->worker.joinable()) impl_->worker.join();
  impl_->file.close();
  if (impl_->write_failed) return VideoLogError::kWriteFailed;
  return std::monostate{};
}

uint64_t VideoLogWriter::frames_written() const { return impl_->written; }
uint64_t VideoLogWriter::frames_dropped() const { return impl_->dropped; }
std::string VideoLogWriter::write_error() const {
  std::lock_guard lock(impl_->mutex);
  return impl_->write_error;
}

// --- reader ---

struct VideoLogReader::Impl {
  std::ifstream file;
  uint32_t version = 0;
  uint32_t fourcc = 0;
  struct Entry {
    uint64_t offset;  // of the record body, after its size field
    uint32_t bytes;
    int64_t stamp_us;
  };
  std::vector<Entry> index;
  std::vector<uint8_t> buffer;
};

VideoLogReader::VideoLogReader(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
VideoLogReader::~VideoLogReader() = default;

Result<std::unique_ptr<VideoLogReader>, VideoLogError> VideoLogReader::open(
    const std::filesystem::path& path) {
  auto impl = std::make_unique<Impl>();
  impl->file.open(path, std::ios::binary);
  if (!impl->file) return VideoLogError::kOpenFailed;
  uint8_t header[kHeaderBytes];
  if (!impl->file.read(reinterpret_cast<char*>(header), kHeaderBytes)) {
    return VideoLogError::kBadFormat;
  }
  ByteReader hr(header + 8, 8);
  const uint32_t version = hr.u32();
  impl->fourcc = hr.u32();
  if (std::memcmp(header, kMagic, 8) != 0 || version < kFirstVersion || version > kVersion ||
      impl->fourcc != kFourccMjpg) {
    return VideoLogError::kBadFormat;
  }
  impl->version = version;
  // index the records: size fields chain them; a truncated last record ends the log
  impl->file.seekg(0, std::ios::end);
  const uint64_t file_bytes = static_cast<uint64_t>(impl->file.tellg());
  uint64_t pos = kHeaderBytes;
  while (pos + 4 + 8 <= file_bytes) {
    uint8_t prefix[12];
    impl->file.seekg(static_cast<std::streamoff>(pos));
    if (!impl->file.read(reinterpret_cast<char*>(prefix), 12)) break;
    ByteReader pr(prefix, 12);
    const uint32_t bytes = pr.u32();
    const int64_t stamp_us = pr.i64();
    if (bytes < 8 || bytes > kMaxRecordBytes || pos + 4 + bytes > file_bytes) break;
    impl->index.push_back({pos + 4, bytes, stamp_us});
    pos += 4 + static_cast<uint64_t>(bytes);
  }
  impl->file.clear();
  return std::unique_ptr<VideoLogReader>(new VideoLogReader(std::move(impl)));
}

size_t VideoLogReader::frame_count() const { return impl_->index.size(); }

int64_t VideoLogReader::stamp_us(size_t index) const { return impl_->index.at(index).stamp_us; }

size_t VideoLogReader::index_at(int64_t stamp_us) const {
  const auto& idx = impl_->index;
  auto it = std::upper_bound(idx.begin(), idx.end(), stamp_us,
                             [](int64_t t, const Impl::Entry& e) { return t < e.stamp_us; });
  return it == idx.begin() ? 0 : static_cast<size_t>(std::distance(idx.begin(), it) - 1);
}

Result<VideoLogRecord, VideoLogError> VideoLogReader::read(size_t index) {
  if (index >= impl_->index.size()) return VideoLogError::kOutOfRange;
  const auto& e = impl_->index[index];
  impl_->buffer.resize(e.bytes);
  impl_->file.seekg(static_cast<std::streamoff>(e.offset));
  if (!impl_->file.read(reinterpret_cast<char*>(impl_->buffer.data()), e.bytes)) {
    impl_->file.clear();
    return VideoLogError::kBadFormat;
  }
  ByteReader r(impl_->buffer.data(), impl_->buffer.size());
  VideoLogRecord rec;
  rec.stamp_us = r.i64();
  rec.keyframe = (r.u8() & kFlagKeyframe) != 0;
  const auto [jpeg, jpeg_bytes] = r.bytes();
  const uint32_t overlay_count = r.u32();
  if (r.failed() || overlay_count > e.bytes) return VideoLogError::kBadFormat;
  rec.overlays.resize(overlay_count);
  for (auto& o : rec.overlays) {
    if (!parse_overlay(&r, &o)) return VideoLogError::kBadFormat;
  }
  rec.text = r.string();
  if (r.failed()) return VideoLogError::kBadFormat;
  if (impl_->version >= 2) {
    const uint32_t plane_count = r.u32();
    if (r.failed() || plane_count > kMaxPlanes) return VideoLogError::kBadFormat;
    for (uint32_t i = 0; i < plane_count; ++i) {
      if (!parse_plane(&r, &rec)) return VideoLogError::kBadFormat;
    }
  }
  rec.image = media::decode_image(
      cv::Mat(1, static_cast<int>(jpeg_bytes), CV_8UC1, const_cast<uint8_t*>(jpeg)),
      cv::IMREAD_UNCHANGED);
  if (rec.image.empty()) return VideoLogError::kDecodeFailed;
  for (const cv::Mat* plane : {&rec.depth_m, &rec.object_ids, &rec.class_ids}) {
    if (!plane->empty() && plane->size() != rec.image.size()) return VideoLogError::kBadFormat;
  }
  return rec;
}

// --- player / exporter ---

void draw_overlays(const std::vector<Overlay>& overlays, cv::Mat* image_bgr) {
  if (image_bgr->type() == CV_8UC1) cv::cvtColor(*image_bgr, *image_bgr, cv::COLOR_GRAY2BGR);
  for (const auto& o : overlays) {
    const int thickness = std::max(1, static_cast<int>(std::lround(o.thickness_px)));
    const cv::Vec4f& g = o.geometry_px;
    switch (o.kind) {
      case Overlay::Kind::kCircle:
        cv::circle(*image_bgr, cv::Point(cvRound(g[0]), cvRound(g[1])), cvRound(g[2]), o.colour_bgr,
                   thickness, cv::LINE_AA);
        break;
      case Overlay::Kind::kLine:
        cv::line(*image_bgr, cv::Point(cvRound(g[0]), cvRound(g[1])),
                 cv::Point(cvRound(g[2]), cvRound(g[3])), o.colour_bgr, thickness, cv::LINE_AA);
        break;
      case Overlay::Kind::kRectangle:
        cv::rectangle(*image_bgr,
                      cv::Rect(cvRound(g[0]), cvRound(g[1]), cvRound(g[2]), cvRound(g[3])),
                      o.colour_bgr, thickness, cv::LINE_AA);
        break;
      case Overlay::Kind::kText:
        cv::putText(*image_bgr, o.text, cv::Point(cvRound(g[0]), cvRound(g[1])),
                    cv::FONT_HERSHEY_SIMPLEX, g[2], o.colour_bgr, thickness, cv::LINE_AA);
        break;
    }
  }
}

void draw_text_block(const std::string& text, cv::Mat* image_bgr) {
  if (image_bgr->type() == CV_8UC1) cv::cvtColor(*image_bgr, *image_bgr, cv::COLOR_GRAY2BGR);
  constexpr double kScale = 0.45;
  constexpr int kLineStepPx = 16;
  int y = kLineStepPx;
  size_t start = 0;
  while (start <= text.size()) {
    const size_t end = std::min(text.find('\n', start), text.size());
    const std::string line = text.substr(start, end - start);
    if (!line.empty()) {
      // dark outline under white text: readable on sky and sand alike
      cv::putText(*image_bgr, line, {6, y}, cv::FONT_HERSHEY_SIMPLEX, kScale, {0, 0, 0}, 3,
                  cv::LINE_AA);
      cv::putText(*image_bgr, line, {6, y}, cv::FONT_HERSHEY_SIMPLEX, kScale, {255, 255, 255}, 1,
                  cv::LINE_AA);
    }
    y += kLineStepPx;
    start = end + 1;
  }
}

namespace {

bool export_options_in_range(const VideoLogExportOptions& o) {
  const bool fps_ok =
      o.fps == 0.0 || (std::isfinite(o.fps) && o.fps > 0.0 && o.fps <= kMaxExportFps);
  const bool depth_ok = std::isfinite(o.depth_near_m) && std::isfinite(o.depth_far_m) &&
                        o.depth_near_m > 0.0 && o.depth_far_m > o.depth_near_m &&
                        o.depth_far_m <= kMaxExportDepthM;
  // the image is a decoded JPEG: nothing exact to dump (its PNGs are the lossless picture of it)
  const bool raw_ok = o.raw_dir.empty() || o.plane != VideoLogPlane::kImage;
  return fps_ok && depth_ok && raw_ok;
}

// the record's plane an export asks for; nullptr for the image
const cv::Mat* plane_of(const VideoLogRecord& rec, VideoLogPlane plane) {
  switch (plane) {
    case VideoLogPlane::kDepth:
      return &rec.depth_m;
    case VideoLogPlane::kObjectIds:
      return &rec.object_ids;
    case VideoLogPlane::kClassIds:
      return &rec.class_ids;
    case VideoLogPlane::kImage:
      break;
  }
  return nullptr;
}

// ffmpeg's pipe, closed on every way out
struct PipeCloser {
  void operator()(FILE* f) const { pclose(f); }
};

}  // namespace

Result<size_t, VideoLogError> export_video_log(const std::filesystem::path& vlog_path,
                                               const VideoLogExportOptions& options) {
  if (!export_options_in_range(options)) return VideoLogError::kBadOption;
  auto reader = VideoLogReader::open(vlog_path);
  if (!reader) return reader.error();
  VideoLogReader& log = *reader.value();
  const size_t n = log.frame_count();

  // frame rate from the median frame interval when not given
  double fps = options.fps;
  if (fps <= 0.0) {
    fps = 10.0;
    if (n >= 2) {
      std::vector<int64_t> dt;
      for (size_t i = 1; i < n; ++i) dt.push_back(log.stamp_us(i) - log.stamp_us(i - 1));
      if (!dt.empty()) {
        std::nth_element(dt.begin(), dt.begin() + dt.size() / 2, dt.end());
        if (dt[dt.size() / 2] > 0) fps = 1e6 / static_cast<double>(dt[dt.size() / 2]);
      }
    }
  }

  media::VideoFileWriter video;
  std::unique_ptr<FILE, PipeCloser> ffmpeg;
  cv::Size video_size;
  size_t exported = 0;
  for (size_t i = 0; i < n; ++i) {
    auto rec = log.read(i);
    if (!rec) return rec.error();
    // the picture: the image, or the plane in false colour (a log of colour only fails on frame 0,
    // before anything is written)
    const cv::Mat* plane = plane_of(*rec, options.plane);
    if (plane != nullptr && plane->empty()) return VideoLogError::kNoSuchPlane;
    if (i == 0) {
      for (const auto* dir : {&options.png_dir, &options.raw_dir}) {
        std::error_code ec;
        if (!dir->empty()) std::filesystem::create_directories(*dir, ec);
        if (ec) return VideoLogError::kExportFailed;
      }
    }
    cv::Mat frame;
    if (plane == nullptr) {
      frame = rec->image;
      if (frame.type() == CV_8UC1) cv::cvtColor(frame, frame, cv::COLOR_GRAY2BGR);
    } else if (options.plane == VideoLogPlane::kDepth) {
      frame = false_colour_depth(*plane, options.depth_near_m, options.depth_far_m);
    } else {
      frame = false_colour_ids(*plane);
    }
    if (options.draw_overlays) draw_overlays(rec->overlays, &frame);
    if (options.draw_text) draw_text_block(rec->text, &frame);
    if (!options.png_dir.empty()) {
      char name[32];
      std::snprintf(name, sizeof(name), "frame_%06zu.png", i);
      if (!media::write_image((options.png_dir / name).string(), frame)) {
        return VideoLogError::kExportFailed;
      }
    }
    if (!options.raw_dir.empty()) {
      char name[48];
      std::snprintf(name, sizeof(name), "%s_%06zu.npy", to_string(options.plane), i);
      if (!write_npy(options.raw_dir / name, *plane)) return VideoLogError::kExportFailed;
    }
    if (!options.mp4_path.empty()) {
      if (i == 0) {
        // OpenCV's own MPEG-4 writer first; ffmpeg through a pipe if this OpenCV lacks it
        video_size = frame.size();
        video.open(options.mp4_path.string(), media::fourcc('m', 'p', '4', 'v'), fps, video_size);
        if (!video.is_open()) {
          const std::string cmd = "ffmpeg -y -loglevel error -f rawvideo -pix_fmt bgr24 -s " +
                                  std::to_string(video_size.width) + "x" +
                                  std::to_string(video_size.height) + " -r " + std::to_string(fps) +
                                  " -i - -c:v mpeg4 -q:v 3 '" + options.mp4_path.string() + "'";
          ffmpeg.reset(popen(cmd.c_str(), "w"));
          if (!ffmpeg) return VideoLogError::kExportFailed;
        }
      }
      if (frame.size() != video_size) cv::resize(frame, frame, video_size);
      if (video.is_open()) {
        video.write(frame);
      } else if (ffmpeg) {
        const cv::Mat contiguous = frame.isContinuous() ? frame : frame.clone();
        fwrite(contiguous.data, 1, contiguous.total() * contiguous.elemSize(), ffmpeg.get());
      }
    }
    ++exported;
  }
  if (video.is_open()) video.release();
  if (ffmpeg && pclose(ffmpeg.release()) != 0) return VideoLogError::kExportFailed;
  return exported;
}

}  // namespace uavsim::vision
