// GlContext: the one seam between camera rendering and the way an OpenGL context is obtained.
// Two backends, a class each: OSMesa (osmesa_context.*: software, llvmpipe, no display) and EGL
// (egl_context.*: Mesa's surfaceless platform on llvmpipe, or a GPU through EGL's device platform).
// OSMesa stays the default (see make_gl_context); Mesa is dropping OSMesa, EGL is its successor.
//
// One backend per process where a GPU is involved: MuJoCo 2.2 resolves its GL entry points once, at
// the first mjr_makeContext, so the first backend to draw decides how every later draw call is
// dispatched. On Mesa both backends share one dispatch library (libglapi), which is why a test can
// render a scene with OSMesa and then with EGL in one process (OSMesa first); a GPU's EGL driver
// does not share it (egl_context.cpp, EglApi).
#pragma once

#include <memory>
#include <string>
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

  // Backend name, as accepted by make_gl_context ("osmesa", "egl").
  virtual std::string_view name() const = 0;

  // What renders, for the startup log: the platform or device and, while the context is current
  // on the calling thread, the GL renderer and version strings ("" if the backend knows nothing).
  virtual std::string detail() const { return {}; }
};

// The backends make_gl_context knows, and "auto", for messages and option checks.
inline constexpr const char* kGlBackendNames = "egl, osmesa or auto";

// Creates a GL context of the named backend: "osmesa" (also ""), "egl", or "auto": EGL when it
// creates a context, else OSMesa, with EGL's error in *fallback_reason (if given; left empty when
// EGL worked). The new context is not current. Throws std::invalid_argument naming the backend and
// the known ones for an unknown name, and std::runtime_error when the backend (for auto: both)
// cannot create a context (startup error).
//
// OSMesa is the default because it is what every test and figure so far was made with; EGL renders
// the same frames (tests/server/render/gl_backend_test.cpp compares them) and is the one to pick
// where OSMesa is missing (Mesa >= 25.1) or a GPU is present.
std::unique_ptr<GlContext> make_gl_context(std::string_view backend = "osmesa",
                                           std::string* fallback_reason = nullptr);

}  // namespace uavsim::server::render
