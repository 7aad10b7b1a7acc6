// GlContext: the one seam between camera rendering and the way an OpenGL context is obtained.
// OSMesa (software, llvmpipe, no display) is the default backend; Mesa is dropping OSMesa, so
// another backend (EGL surfaceless or a GPU) is one more class implementing this interface plus one
// line in make_gl_context.
#pragma once

#include <memory>
#include <string_view>

namespace uavsim::server::render {

// An OpenGL context that MuJoCo's renderer (mjr_*) can draw into with mjFB_OFFSCREEN. It owns only
// a minimal default framebuffer: every camera image goes to MuJoCo's own offscreen framebuffer
// object. A context is current on at most one thread at a time; all methods of one object are
// called from one thread.
class GlContext {
 public:
  virtual ~GlContext() = default;
  GlContext() = default;
  GlContext(const GlContext&) = delete;
  GlContext& operator=(const GlContext&) = delete;

  // Makes this context current on the calling thread; cheap when it already is.
  // Returns false when the backend refuses (the GL state is then undefined).
  virtual bool make_current() = 0;

  // Detaches this context from the calling thread if it is current there; no-op otherwise.
  virtual void release() = 0;

  // Backend name, as accepted by make_gl_context ("osmesa").
  virtual std::string_view name() const = 0;
};

// Creates a GL context of the named backend; "" and "osmesa" select OSMesa. The new context is not
// current. Throws std::invalid_argument naming the backend and the known ones for an unknown name,
// and std::runtime_error when the backend exists but cannot create a context (startup error).
std::unique_ptr<GlContext> make_gl_context(std::string_view backend = "osmesa");

}  // namespace uavsim::server::render
