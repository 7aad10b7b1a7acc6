// EGL backend of GlContext: a desktop OpenGL context without a window or X server. Mesa's
// surfaceless platform runs it on llvmpipe (no GPU needed), and the same code picks a GPU through
// EGL's device platform where the machine has one. Unlike OSMesa, which Mesa's newest releases no
// longer ship, EGL is supported by every current driver, so it is the backend with a future.
// Only egl_context.cpp includes <EGL/egl.h>; this header keeps the handles opaque.
#pragma once

#include <memory>
#include <string>

#include "render/gl_context.hpp"

namespace uavsim::server::render {

class EglContext final : public GlContext {
 public:
  // Opens the process's EGL display (shared by every EglContext: the first one picks it, the last
  // one terminates it) and creates a desktop-GL compatibility context on it, with a small pbuffer
  // as its default framebuffer (camera images use MuJoCo's offscreen FBO, not this surface).
  // Displays are tried in this order: a hardware EGL device (EGL_EXT_device_enumeration +
  // EGL_EXT_platform_device), then Mesa's surfaceless platform (EGL_MESA_platform_surfaceless),
  // which renders with llvmpipe. Throws std::runtime_error naming the step that failed and the EGL
  // error when no display gives a context.
  explicit EglContext(int surface_width = 64, int surface_height = 64);
  ~EglContext() override;

  bool make_current() override;
  void release() override;
  std::string_view name() const override { return "egl"; }
  std::string detail() const override;

  struct Display;  // the shared EGL display (egl_context.cpp)

 private:
  std::shared_ptr<Display> display_;
  void* config_ = nullptr;   // EGLConfig
  void* context_ = nullptr;  // EGLContext
  void* surface_ = nullptr;  // EGLSurface; EGL_NO_SURFACE when the display has no pbuffer config
};

}  // namespace uavsim::server::render
