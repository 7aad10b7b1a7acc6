// A small VLOG with depth and segmentation planes of known values, and a .npy reader: the
// exporter's tests (video_log_export_test.cpp, videolog_export_cli_test.cpp).
#pragma once

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <opencv2/core.hpp>
#include <string>

#include "uavsim/vision/video_log.hpp"

namespace uavsim::vision::test {

constexpr int kPlaneWidthPx = 40;
constexpr int kPlaneHeightPx = 30;

// frame i's planes: depth 1 + x + i/4 m with row 0 nothing measured (NaN), (5, 0) nearer than the
// default near (0.5 m) and (6, 39) farther than the default far (500 m); object id x/4 + 10 in the
// lower half (0 in the top-left 4 x 4: nothing hit), class id object id % 8
inline VideoLogFrame plane_frame(int i) {
  VideoLogFrame f;
  f.stamp_us = 100'000LL * i;
  f.image = cv::Mat(kPlaneHeightPx, kPlaneWidthPx, CV_8UC3, cv::Scalar::all(10 * i));
  f.depth_m = cv::Mat(kPlaneHeightPx, kPlaneWidthPx, CV_32FC1);
  f.object_ids = cv::Mat(kPlaneHeightPx, kPlaneWidthPx, CV_16UC1);
  f.class_ids = cv::Mat(kPlaneHeightPx, kPlaneWidthPx, CV_16UC1);
  for (int y = 0; y < kPlaneHeightPx; ++y) {
    for (int x = 0; x < kPlaneWidthPx; ++x) {
      f.depth_m.at<float>(y, x) =
          y == 0 ? std::numeric_limits<float>::quiet_NaN() : 1.0f + x + 0.25f * i;
      const int id = (x < 4 && y < 4) ? 0 : x / 4 + (y >= kPlaneHeightPx / 2 ? 10 : 0);
      f.object_ids.at<uint16_t>(y, x) = static_cast<uint16_t>(id);
      f.class_ids.at<uint16_t>(y, x) = static_cast<uint16_t>(id % 8);
    }
  }
  f.depth_m.at<float>(5, 0) = 0.5f;
  f.depth_m.at<float>(6, 39) = 500.0f;
  f.overlays = {Overlay::circle({20, 15}, 5, {0, 255, 0}, 3.0f)};
  f.text = "frame " + std::to_string(i);
  return f;
}

// frames plane_frame(0..count-1), or the same without planes (a colour-only log)
inline bool write_plane_log(const std::filesystem::path& path, int count, bool with_planes = true) {
  auto writer = VideoLogWriter::open(path, {90, 64, nullptr});
  if (!writer) return false;
  for (int i = 0; i < count; ++i) {
    VideoLogFrame f = plane_frame(i);
    if (!with_planes) f.depth_m = f.object_ids = f.class_ids = cv::Mat();
    if (!(*writer)->submit(f)) return false;
  }
  return (*writer)->close().ok() && (*writer)->frames_written() == static_cast<uint64_t>(count);
}

// a .npy file as the exporter documents it (format 1.0, a dict header): its descr, shape and data
struct Npy {
  std::string descr;
  int rows = -1, cols = -1;
  std::string data;
};

inline Npy read_npy(const std::filesystem::path& path) {
  Npy npy;
  std::ifstream in(path, std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (bytes.size() < 10 || bytes.compare(0, 8, std::string("\x93NUMPY\x01\x00", 8)) != 0)
    return npy;
  const size_t header_len = static_cast<uint8_t>(bytes[8]) | (static_cast<uint8_t>(bytes[9]) << 8);
  if ((10 + header_len) % 64 != 0 || bytes.size() < 10 + header_len) return npy;
  const std::string dict = bytes.substr(10, header_len);
  const size_t d = dict.find("'descr': '");
  if (d != std::string::npos) npy.descr = dict.substr(d + 10, 3);
  if (dict.find("'fortran_order': False") == std::string::npos || dict.back() != '\n') return npy;
  const size_t s = dict.find("'shape': (");
  if (s != std::string::npos) std::sscanf(dict.c_str() + s + 10, "%d, %d", &npy.rows, &npy.cols);
  npy.data = bytes.substr(10 + header_len);
  return npy;
}

// a Mat's bytes row by row
inline std::string mat_bytes(const cv::Mat& m) {
  std::string b;
  for (int y = 0; y < m.rows; ++y)
    b.append(reinterpret_cast<const char*>(m.ptr(y)), m.cols * m.elemSize());
  return b;
}

}  // namespace uavsim::vision::test
