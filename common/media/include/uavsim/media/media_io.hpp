// Image files and codecs (JPEG, PNG, ...) and video files, through OpenCV's imgcodecs and videoio,
// loaded the first time a program needs one of them.
//
// Why not link those two OpenCV modules: on Debian they bring about 220 shared libraries with them
// (GDAL, GStreamer, FFmpeg, ...), and the dynamic loader resolving their symbols cost every process
// that linked them about 0.17 s of CPU at start-up (a server, each mission program, each test that
// starts one), whether it ever wrote an image or not. They live in one module of ours,
// libuavsim_media_io.so, opened here on first use. A program that never encodes a frame or writes a
// video never loads them.
//
// Where the module is looked for, first found wins (module_error() lists them when none loads):
//   - $UAVSIM_MEDIA_IO, when set: that file and nothing else;
//   - beside the program or shared object holding this code: ../LIBDIR/uavsim/ (an install, moved
//     or not) and its own folder (the Python package);
//   - where this build put it (the build tree);
//   - LIBDIR/uavsim/ under the install prefix this build was configured with, then under /usr and
//     /usr/local (a program of one's own linked against the installed client library).
//
// Each function behaves as the OpenCV function it names, exceptions included; when the module
// cannot be loaded it fails the way that function fails (false, an empty Mat, a writer that is not
// open) and the reason is printed once on stderr. Thread-safe.
#pragma once

#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace uavsim::media {

// cv::VideoWriter::fourcc
constexpr int fourcc(char c1, char c2, char c3, char c4) {
  return (c1 & 255) | ((c2 & 255) << 8) | ((c3 & 255) << 16) | ((c4 & 255) << 24);
}

// cv::imencode(ext, image, *out, params)
bool encode_image(const std::string& ext, const cv::Mat& image, std::vector<uchar>* out,
                  const std::vector<int>& params = {});

// cv::imdecode(bytes, flags) (cv::IMREAD_* from <opencv2/imgcodecs.hpp>, a header-only enum)
cv::Mat decode_image(const cv::Mat& bytes, int flags);

// cv::imwrite(path, image)
bool write_image(const std::string& path, const cv::Mat& image);

// cv::VideoWriter: open, write, release. One thread at a time per writer.
class VideoFileWriter {
 public:
  VideoFileWriter() = default;
  ~VideoFileWriter() { release(); }
  VideoFileWriter(const VideoFileWriter&) = delete;
  VideoFileWriter& operator=(const VideoFileWriter&) = delete;

  // false when the container/codec cannot be opened (or the module cannot be loaded)
  bool open(const std::string& path, int fourcc, double fps, cv::Size size, bool is_color = true);
  bool is_open() const { return writer_ != nullptr; }
  void write(const cv::Mat& frame);
  // finishes the file; a writer that is not open does nothing
  void release();

 private:
  void* writer_ = nullptr;
};

// cv::VideoCapture(path, cv::CAP_FFMPEG).isOpened(): whether FFmpeg can read the file
bool ffmpeg_can_open(const std::string& path);

// "" when the module is loaded (loading it now if it was not); else why it cannot be, with every
// place tried
std::string module_error();

}  // namespace uavsim::media
