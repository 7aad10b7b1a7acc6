// The MBZIRC 2017 landing marker (seed 7.1, fig. 7.1b) as an image the project generates itself: a white
// ring with a white cross inside on a dark 1.5 m square. The geometry is vision's LandingMarkerGeometry
// (vision/include/uavsim/vision/marker_detector.hpp), so the detector and the rendered deck agree.
// models/objects/truck_marker.png is this generator's output (tool uavsim-marker-texture; a test checks
// that the committed file matches). Pure: no MuJoCo.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace uavsim::server::objects {

struct MarkerGeometry {
  double square_side_m = 1.5;
  double ring_outer_radius_m = 0.65;
  double ring_inner_radius_m = 0.50;
  double cross_half_length_m = 0.35;
  double cross_half_width_m = 0.06;
};

// An 8-bit RGB image, rows top to bottom.
struct RgbImage {
  int width_px = 0;
  int height_px = 0;
  std::vector<uint8_t> rgb;
};

// Renders the marker into a side_px x side_px image (4x4 supersampled edges).
RgbImage render_marker(const MarkerGeometry& geometry, int side_px);

// Encodes an image as PNG (8-bit RGB, zlib level 9). Deterministic: same image, same bytes.
std::vector<uint8_t> encode_png(const RgbImage& image);

// Writes bytes to a file; returns false (and an error text) on failure.
bool write_file(const std::string& path, const std::vector<uint8_t>& bytes, std::string* error);

}  // namespace uavsim::server::objects
