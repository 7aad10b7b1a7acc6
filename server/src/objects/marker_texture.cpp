#include "objects/marker_texture.hpp"

#include <zlib.h>

#include <cmath>
#include <fstream>

namespace uavsim::server::objects {

namespace {

constexpr uint8_t kWhite = 235;
constexpr uint8_t kDark = 25;

// is the point (x, y) in metres from the centre white?
bool white_at(const MarkerGeometry& g, double x, double y) {
  const double r = std::hypot(x, y);
  if (r >= g.ring_inner_radius_m && r <= g.ring_outer_radius_m) return true;
  const bool horizontal = std::abs(x) <= g.cross_half_length_m && std::abs(y) <= g.cross_half_width_m;
  const bool vertical = std::abs(y) <= g.cross_half_length_m && std::abs(x) <= g.cross_half_width_m;
  return horizontal || vertical;
}

void put_u32(std::vector<uint8_t>* out, uint32_t v) {
  for (int shift = 24; shift >= 0; shift -= 8) out->push_back(static_cast<uint8_t>(v >> shift));
}

// one PNG chunk: length, type, data, CRC-32 of type and data
void put_chunk(std::vector<uint8_t>* out, const char type[4], const std::vector<uint8_t>& data) {
  put_u32(out, static_cast<uint32_t>(data.size()));
  const size_t start = out->size();
  out->insert(out->end(), type, type + 4);
  out->insert(out->end(), data.begin(), data.end());
  const uLong crc = crc32(0L, out->data() + start, static_cast<uInt>(out->size() - start));
  put_u32(out, static_cast<uint32_t>(crc));
}

}  // namespace

RgbImage render_marker(const MarkerGeometry& g, int side_px) {
  RgbImage img;
  img.width_px = img.height_px = side_px;
  img.rgb.resize(static_cast<size_t>(side_px) * side_px * 3);
  const double m_per_px = g.square_side_m / side_px;
  constexpr int kSub = 4;
  for (int row = 0; row < side_px; ++row) {
    for (int col = 0; col < side_px; ++col) {
      // coverage of white over a 4x4 grid of sub-pixel samples
      int white = 0;
      for (int sy = 0; sy < kSub; ++sy) {
        for (int sx = 0; sx < kSub; ++sx) {
          const double x = (col + (sx + 0.5) / kSub) * m_per_px - 0.5 * g.square_side_m;
          const double y = 0.5 * g.square_side_m - (row + (sy + 0.5) / kSub) * m_per_px;
          white += white_at(g, x, y) ? 1 : 0;
        }
      }
      const double f = static_cast<double>(white) / (kSub * kSub);
      const auto v = static_cast<uint8_t>(std::lround(kDark + f * (kWhite - kDark)));
      uint8_t* p = &img.rgb[(static_cast<size_t>(row) * side_px + col) * 3];
      p[0] = p[1] = p[2] = v;
    }
  }
  return img;
}

std::vector<uint8_t> encode_png(const RgbImage& image) {
  std::vector<uint8_t> out = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
  // IHDR: width, height, bit depth 8, colour type 2 (RGB), deflate, adaptive filter, no interlace
  std::vector<uint8_t> ihdr;
  put_u32(&ihdr, static_cast<uint32_t>(image.width_px));
  put_u32(&ihdr, static_cast<uint32_t>(image.height_px));
  ihdr.insert(ihdr.end(), {8, 2, 0, 0, 0});
  put_chunk(&out, "IHDR", ihdr);

  // IDAT: each row prefixed with filter type 0 (none), zlib-compressed
  std::vector<uint8_t> raw;
  const size_t stride = static_cast<size_t>(image.width_px) * 3;
  for (int row = 0; row < image.height_px; ++row) {
    raw.push_back(0);
    raw.insert(raw.end(), image.rgb.begin() + row * stride, image.rgb.begin() + (row + 1) * stride);
  }
  uLongf size = compressBound(static_cast<uLong>(raw.size()));
  std::vector<uint8_t> idat(size);
  compress2(idat.data(), &size, raw.data(), static_cast<uLong>(raw.size()), 9);
  idat.resize(size);
  put_chunk(&out, "IDAT", idat);
  put_chunk(&out, "IEND", {});
  return out;
}

bool write_file(const std::string& path, const std::vector<uint8_t>& bytes, std::string* error) {
  std::ofstream f(path, std::ios::binary);
  f.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  if (!f) {
    if (error) *error = "cannot write " + path;
    return false;
  }
  return true;
}

}  // namespace uavsim::server::objects
