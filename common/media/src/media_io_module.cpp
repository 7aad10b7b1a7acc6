// libuavsim_media_io.so: OpenCV's imgcodecs and videoio behind the table of media_io_table.hpp.
// The only code of ours that links those two OpenCV modules (and the ~220 libraries they bring);
// programs load it through media_io.hpp when they first need an image or a video file.
#include <memory>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>

#include "media_io_table.hpp"

namespace {

using uavsim::media::detail::MediaIoTable;

bool encode(const std::string& ext, const cv::Mat& image, std::vector<uchar>* out,
            const std::vector<int>& params) {
  return cv::imencode(ext, image, *out, params);
}

cv::Mat decode(const cv::Mat& bytes, int flags) { return cv::imdecode(bytes, flags); }

bool write(const std::string& path, const cv::Mat& image) { return cv::imwrite(path, image); }

void* video_open(const std::string& path, int fourcc, double fps, cv::Size size, bool is_color) {
  auto writer = std::make_unique<cv::VideoWriter>();
  if (!writer->open(path, fourcc, fps, size, is_color)) return nullptr;
  return writer.release();
}

void video_write(void* writer, const cv::Mat& frame) {
  static_cast<cv::VideoWriter*>(writer)->write(frame);
}

void video_close(void* writer) {
  auto* w = static_cast<cv::VideoWriter*>(writer);
  w->release();
  delete w;
}

bool ffmpeg_can_open(const std::string& path) {
  return cv::VideoCapture(path, cv::CAP_FFMPEG).isOpened();
}

constexpr MediaIoTable kTable = {uavsim::media::detail::kMediaIoAbiVersion,
                                 sizeof(MediaIoTable),
                                 encode,
                                 decode,
                                 write,
                                 video_open,
                                 video_write,
                                 video_close,
                                 ffmpeg_can_open};

}  // namespace

extern "C" __attribute__((visibility("default"))) const MediaIoTable* uavsim_media_io_table() {
  return &kTable;
}
