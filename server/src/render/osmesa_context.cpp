#include "render/osmesa_context.hpp"

#include <GL/osmesa.h>

#include <stdexcept>
#include <string>

namespace uavsim::server::render {

OsmesaContext::OsmesaContext(int window_width, int window_height)
    : window_width_(window_width),
      window_height_(window_height),
      window_buffer_(static_cast<size_t>(window_width) * window_height) {
  // RGBA, 24-bit depth, 8-bit stencil, no accumulation buffer, no shared lists
  context_ = OSMesaCreateContextExt(OSMESA_RGBA, 24, 8, 0, nullptr);
  if (context_ == nullptr) {
    throw std::runtime_error(
        "osmesa: OSMesaCreateContextExt(OSMESA_RGBA, depth 24, stencil 8) failed");
  }
}

OsmesaContext::~OsmesaContext() {
  release();
  OSMesaDestroyContext(static_cast<OSMesaContext>(context_));
}

bool OsmesaContext::make_current() {
  auto* ctx = static_cast<OSMesaContext>(context_);
  if (OSMesaGetCurrentContext() == ctx) return true;
  return OSMesaMakeCurrent(ctx, window_buffer_.data(), GL_UNSIGNED_BYTE, window_width_,
                           window_height_) == GL_TRUE;
}

void OsmesaContext::release() {
  // a null context and buffer unbind whatever is current on this thread
  if (OSMesaGetCurrentContext() == static_cast<OSMesaContext>(context_)) {
    OSMesaMakeCurrent(nullptr, nullptr, 0, 0, 0);
  }
}

std::string OsmesaContext::detail() const {
  // through OSMesa's own lookup: a plain glGetString call could bind to libGL's, which knows
  // nothing of OSMesa's context
  if (OSMesaGetCurrentContext() != static_cast<OSMesaContext>(context_)) return "software";
  using GetString = const GLubyte* (*)(GLenum);
  auto get_string = reinterpret_cast<GetString>(OSMesaGetProcAddress("glGetString"));
  const GLubyte* renderer = get_string ? get_string(GL_RENDERER) : nullptr;
  const GLubyte* version = get_string ? get_string(GL_VERSION) : nullptr;
  std::string text = "software";
  if (renderer) text += std::string(", ") + reinterpret_cast<const char*>(renderer);
  if (version) text += std::string(", OpenGL ") + reinterpret_cast<const char*>(version);
  return text;
}

}  // namespace uavsim::server::render
