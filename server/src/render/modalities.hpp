// What a camera gives (world text / --camera key modalities=rgb+grey+depth+segmentation).
// MuJoCo-free, for the frame service's users.
#pragma once

namespace uavsim::server::render {

// Colour as RGB (and JPEG), grey, depth (metres along the optical axis) and segmentation (object
// and class per pixel). Depth and segmentation take a second render pass, drawn only for the frames
// someone asked them of.
struct Modalities {
  bool rgb = true;
  bool grey = true;
  bool depth = false;
  bool segmentation = false;
  bool colour() const { return rgb || grey; }
  bool geometry() const { return depth || segmentation; }
};

}  // namespace uavsim::server::render
