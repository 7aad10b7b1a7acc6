// uavsim-marker-texture OUT.png [SIDE_PX]: writes the MBZIRC 2017 landing-marker texture
// (models/objects/truck_marker.png is this tool's output with the defaults).
#include <cstdlib>
#include <iostream>

#include "objects/marker_texture.hpp"

int main(int argc, char** argv) {
  using namespace uavsim::server::objects;
  if (argc < 2 || argc > 3) {
    std::cerr << "usage: uavsim-marker-texture OUT.png [SIDE_PX (default 512)]\n";
    return 2;
  }
  const int side = argc == 3 ? std::atoi(argv[2]) : 512;
  if (side < 16 || side > 8192) {
    std::cerr << "uavsim-marker-texture: SIDE_PX must be in [16, 8192]\n";
    return 2;
  }
  std::string error;
  if (!write_file(argv[1], encode_png(render_marker(MarkerGeometry{}, side)), &error)) {
    std::cerr << "uavsim-marker-texture: " << error << "\n";
    return 1;
  }
  return 0;
}
