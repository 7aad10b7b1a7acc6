// The table of entry points libuavsim_media_io.so hands the loader in media_io.cpp: the one place
// the module and the programs that load it must agree on. Both sides are built by the same build
// with the same compiler and OpenCV, so the table passes C++ types; `abi_version` and `table_size`
// still catch a module from another build found first (an old install), which is refused.
#pragma once

#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace uavsim::media::detail {

// bump when a member's signature or the order changes
inline constexpr int kMediaIoAbiVersion = 1;

struct MediaIoTable {
  int abi_version;
  std::size_t table_size;
  // cv::imencode, cv::imdecode, cv::imwrite, exceptions as they throw
  bool (*encode)(const std::string& ext, const cv::Mat& image, std::vector<uchar>* out,
                 const std::vector<int>& params);
  cv::Mat (*decode)(const cv::Mat& bytes, int flags);
  bool (*write)(const std::string& path, const cv::Mat& image);
  // a cv::VideoWriter behind an opaque handle: nullptr when it does not open
  void* (*video_open)(const std::string& path, int fourcc, double fps, cv::Size size,
                      bool is_color);
  void (*video_write)(void* writer, const cv::Mat& frame);
  void (*video_close)(void* writer);  // releases (finishes the file) and frees
  // cv::VideoCapture(path, cv::CAP_FFMPEG).isOpened()
  bool (*ffmpeg_can_open)(const std::string& path);
};

}  // namespace uavsim::media::detail

// the module's one exported symbol
extern "C" const uavsim::media::detail::MediaIoTable* uavsim_media_io_table();
