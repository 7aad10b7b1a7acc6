// The depth and id planes of a video log as pictures (false colour) and as exact dumps (.npy), for
// export_video_log.
#include <algorithm>
#include <bit>
#include <cassert>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "uavsim/vision/video_log.hpp"

namespace uavsim::vision {

namespace {

constexpr double kGoldenAngleDeg = 137.50776405003785;  // 360 (1 - 1 / phi)
constexpr double kIdSaturation = 0.85;
constexpr double kIdValueOdd = 1.0;
constexpr double kIdValueEven = 0.7;

// every id's colour, computed once (65536 x 3 bytes)
const std::vector<cv::Vec3b>& id_palette() {
  static const std::vector<cv::Vec3b> palette = [] {
    std::vector<cv::Vec3b> p(65536);
    for (size_t id = 0; id < p.size(); ++id) p[id] = id_colour_bgr(static_cast<uint16_t>(id));
    return p;
  }();
  return palette;
}

}  // namespace

cv::Mat false_colour_depth(const cv::Mat& depth_m, double near_m, double far_m) {
  assert(depth_m.type() == CV_32FC1 && near_m > 0.0 && far_m > near_m);
  // (z, near, far) => level 255 (near) .. 0 (far) on a log scale; NaN => masked out, black
  const double log_span = std::log(far_m / near_m);
  cv::Mat level(depth_m.size(), CV_8UC1);
  cv::Mat valid(depth_m.size(), CV_8UC1);
  for (int y = 0; y < depth_m.rows; ++y) {
    const float* z = depth_m.ptr<float>(y);
    uint8_t* l = level.ptr<uint8_t>(y);
    uint8_t* v = valid.ptr<uint8_t>(y);
    for (int x = 0; x < depth_m.cols; ++x) {
      v[x] = std::isnan(z[x]) ? 0 : 255;
      const double clamped = std::isnan(z[x]) ? far_m : std::clamp<double>(z[x], near_m, far_m);
      l[x] =
          static_cast<uint8_t>(std::lround(255.0 * (1.0 - std::log(clamped / near_m) / log_span)));
    }
  }
  cv::Mat turbo;
  cv::applyColorMap(level, turbo, cv::COLORMAP_TURBO);
  cv::Mat out(depth_m.size(), CV_8UC3, cv::Scalar::all(0));
  turbo.copyTo(out, valid);
  return out;
}

cv::Vec3b id_colour_bgr(uint16_t id) {
  if (id == 0) return {0, 0, 0};
  // HSV => RGB: chroma c in the hue's sextant, the second-largest component x, the offset m
  const double h = std::fmod(id * kGoldenAngleDeg, 360.0) / 60.0;
  const double v = id % 2 == 1 ? kIdValueOdd : kIdValueEven;
  const double c = v * kIdSaturation;
  const double x = c * (1.0 - std::abs(std::fmod(h, 2.0) - 1.0));
  const double m = v - c;
  double r = 0, g = 0, b = 0;
  switch (static_cast<int>(h)) {
    case 0:
      r = c, g = x;
      break;
    case 1:
      r = x, g = c;
      break;
    case 2:
      g = c, b = x;
      break;
    case 3:
      g = x, b = c;
      break;
    case 4:
      r = x, b = c;
      break;
    default:
      r = c, b = x;
      break;
  }
  auto byte = [m](double u) { return static_cast<uint8_t>(std::lround(255.0 * (u + m))); };
  return {byte(b), byte(g), byte(r)};
}

cv::Mat false_colour_ids(const cv::Mat& ids) {
  assert(ids.type() == CV_16UC1);
  const std::vector<cv::Vec3b>& palette = id_palette();
  cv::Mat out(ids.size(), CV_8UC3);
  for (int y = 0; y < ids.rows; ++y) {
    const uint16_t* in = ids.ptr<uint16_t>(y);
    cv::Vec3b* o = out.ptr<cv::Vec3b>(y);
    for (int x = 0; x < ids.cols; ++x) o[x] = palette[in[x]];
  }
  return out;
}

bool write_npy(const std::filesystem::path& path, const cv::Mat& plane) {
  // NumPy's format 1.0: magic, version, u16 header length, a Python dict literal padded with spaces
  // to a multiple of 64 bytes ending in '\n', then the data in C order
  static_assert(std::endian::native == std::endian::little, "the .npy headers say little-endian");
  const char* descr = plane.type() == CV_32FC1 ? "<f4" : plane.type() == CV_16UC1 ? "<u2" : nullptr;
  if (descr == nullptr) return false;
  std::string dict = std::string("{'descr': '") + descr + "', 'fortran_order': False, 'shape': (" +
                     std::to_string(plane.rows) + ", " + std::to_string(plane.cols) + "), }";
  constexpr size_t kPreambleBytes = 10;  // magic (6), version (2), header length (2)
  const size_t total = (kPreambleBytes + dict.size() + 1 + 63) / 64 * 64;
  dict.append(total - kPreambleBytes - dict.size() - 1, ' ');
  dict.push_back('\n');
  std::string head("\x93NUMPY\x01\x00", 8);
  head.push_back(static_cast<char>(dict.size() & 0xff));
  head.push_back(static_cast<char>(dict.size() >> 8));
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(head.data(), static_cast<std::streamsize>(head.size()));
  out.write(dict.data(), static_cast<std::streamsize>(dict.size()));
  const size_t row_bytes = plane.cols * plane.elemSize();
  for (int y = 0; y < plane.rows; ++y)
    out.write(reinterpret_cast<const char*>(plane.ptr(y)), static_cast<std::streamsize>(row_bytes));
  out.close();
  return static_cast<bool>(out);
}

}  // namespace uavsim::vision
