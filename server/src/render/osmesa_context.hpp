// OSMesa backend of GlContext: Mesa's off-screen software renderer, needs no display and no GPU.
// Only osmesa_context.cpp includes <GL/osmesa.h>; this header keeps the handle opaque.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "render/gl_context.hpp"

namespace uavsim::server::render {

class OsmesaContext final : public GlContext {
 public:
  // Creates an RGBA context with a 24-bit depth and 8-bit stencil buffer, bound (on make_current)
  // to a small colour buffer of window_width x window_height; camera images use MuJoCo's offscreen
  // FBO, not this buffer. Throws std::runtime_error if OSMesa cannot create the context.
  explicit OsmesaContext(int window_width = 64, int window_height = 64);
  ~OsmesaContext() override;

  bool make_current() override;
  void release() override;
  std::string_view name() const override { return "osmesa"; }
  std::string detail() const override;

 private:
  void* context_ = nullptr;  // OSMesaContext
  int window_width_;
  int window_height_;
  std::vector<uint32_t> window_buffer_;  // RGBA8 pixels of the default framebuffer
};

}  // namespace uavsim::server::render
