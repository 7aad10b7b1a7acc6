#include "render/egl_context.hpp"

#include <EGL/egl.h>
#include <EGL/eglext.h>
#include <dlfcn.h>
#include <link.h>

#include <cstdio>
#include <cstring>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

namespace uavsim::server::render {

namespace {

constexpr int kMaxDevices = 16;  // EGL devices looked at; a machine has a handful at most

// GL_RENDERER and GL_VERSION, from <GL/gl.h>: this file queries them through eglGetProcAddress
// rather than linking libGL, whose glGetString would dispatch to whichever library defines it first
constexpr unsigned kGlRenderer = 0x1F01;
constexpr unsigned kGlVersion = 0x1F02;
using GlGetString = const unsigned char* (*)(unsigned);

// libEGL, opened at run time rather than linked. MuJoCo 2.2 resolves its GL entry points once per
// process, at the first mjr_makeContext, through the first of eglGetProcAddress,
// OSMesaGetProcAddress and glXGetProcAddressARB that the process's global symbols offer. Linked
// libEGL would always win, and its (GLVND) entry points draw nothing while an OSMesa context is
// current: OSMesa renderers failed in mjr_makeContext ("gladLoadGL error"). So libEGL is opened
// local. Mesa's EGL needs no more: its contexts and OSMesa's share Mesa's dispatch library
// (libglapi), so the entry points MuJoCo takes from OSMesa draw into whichever of the two is
// current, in any order, on any thread. Another vendor's EGL (a GPU driver) dispatches only
// through its own: there libEGL is made global once a context exists (publish_egl), so that
// MuJoCo takes eglGetProcAddress, and OSMesa cannot be used in the same process after that.
struct EglApi {
  void* library = nullptr;
  PFNEGLGETPROCADDRESSPROC GetProcAddress = nullptr;
  PFNEGLGETERRORPROC GetError = nullptr;
  PFNEGLQUERYSTRINGPROC QueryString = nullptr;
  PFNEGLINITIALIZEPROC Initialize = nullptr;
  PFNEGLTERMINATEPROC Terminate = nullptr;
  PFNEGLBINDAPIPROC BindAPI = nullptr;
  PFNEGLCHOOSECONFIGPROC ChooseConfig = nullptr;
  PFNEGLCREATECONTEXTPROC CreateContext = nullptr;
  PFNEGLDESTROYCONTEXTPROC DestroyContext = nullptr;
  PFNEGLCREATEPBUFFERSURFACEPROC CreatePbufferSurface = nullptr;
  PFNEGLDESTROYSURFACEPROC DestroySurface = nullptr;
  PFNEGLMAKECURRENTPROC MakeCurrent = nullptr;
  PFNEGLGETCURRENTCONTEXTPROC GetCurrentContext = nullptr;
  PFNEGLRELEASETHREADPROC ReleaseThread = nullptr;
};

// libEGL's entry points, loaded on first use (thread-safe); throws if libEGL is missing
const EglApi& egl() {
  static const EglApi api = [] {
    EglApi a;
    a.library = dlopen("libEGL.so.1", RTLD_NOW | RTLD_LOCAL);
    if (a.library == nullptr) {
      throw std::runtime_error(std::string("egl: cannot open libEGL.so.1 (Debian: libegl1): ") +
                               dlerror());
    }
    bool complete = true;
    auto load = [&](auto* fn, const char* name) {
      *fn = reinterpret_cast<std::remove_pointer_t<decltype(fn)>>(dlsym(a.library, name));
      complete = complete && *fn != nullptr;
    };
    load(&a.GetProcAddress, "eglGetProcAddress");
    load(&a.GetError, "eglGetError");
    load(&a.QueryString, "eglQueryString");
    load(&a.Initialize, "eglInitialize");
    load(&a.Terminate, "eglTerminate");
    load(&a.BindAPI, "eglBindAPI");
    load(&a.ChooseConfig, "eglChooseConfig");
    load(&a.CreateContext, "eglCreateContext");
    load(&a.DestroyContext, "eglDestroyContext");
    load(&a.CreatePbufferSurface, "eglCreatePbufferSurface");
    load(&a.DestroySurface, "eglDestroySurface");
    load(&a.MakeCurrent, "eglMakeCurrent");
    load(&a.GetCurrentContext, "eglGetCurrentContext");
    load(&a.ReleaseThread, "eglReleaseThread");
    if (!complete) throw std::runtime_error("egl: libEGL.so.1 lacks EGL 1.4 entry points");
    return a;
  }();
  return api;
}

// Makes libEGL's symbols global (see EglApi): for a display of another vendor than Mesa.
void publish_egl() {
  static std::once_flag once;
  std::call_once(once, [] { dlopen("libEGL.so.1", RTLD_NOW | RTLD_NOLOAD | RTLD_GLOBAL); });
}

std::string egl_error_text() {
  const EGLint e = egl().GetError();
  char hex[16];
  std::snprintf(hex, sizeof(hex), "0x%04X", static_cast<unsigned>(e));
  return hex;
}

bool has_extension(const char* list, const char* name) {
  if (list == nullptr) return false;
  const size_t n = std::strlen(name);
  for (const char* p = list; (p = std::strstr(p, name)) != nullptr; p += n) {
    const bool starts = p == list || p[-1] == ' ';
    const bool ends = p[n] == '\0' || p[n] == ' ';
    if (starts && ends) return true;
  }
  return false;
}

// RGBA8 with depth and stencil, rendering desktop OpenGL: MuJoCo's offscreen FBO takes its own
// formats, but its mjr_makeContext reads the default framebuffer's too
std::vector<EGLint> config_attribs(EGLint surface_type) {
  return {EGL_SURFACE_TYPE,
          surface_type,
          EGL_RENDERABLE_TYPE,
          EGL_OPENGL_BIT,
          EGL_RED_SIZE,
          8,
          EGL_GREEN_SIZE,
          8,
          EGL_BLUE_SIZE,
          8,
          EGL_ALPHA_SIZE,
          8,
          EGL_DEPTH_SIZE,
          24,
          EGL_STENCIL_SIZE,
          8,
          EGL_NONE};
}

std::optional<EGLConfig> choose_config(EGLDisplay display, EGLint surface_type) {
  const std::vector<EGLint> attribs = config_attribs(surface_type);
  EGLConfig config = nullptr;
  EGLint count = 0;
  if (egl().ChooseConfig(display, attribs.data(), &config, 1, &count) != EGL_TRUE || count < 1) {
    return std::nullopt;
  }
  return config;
}

}  // namespace

// One EGL display for the whole process: eglTerminate on a display destroys every context on it,
// so contexts on other render threads share it and the last one out terminates it.
struct EglContext::Display {
  EGLDisplay handle = EGL_NO_DISPLAY;
  std::string description;      // which platform and device, for the startup log
  bool surfaceless_ok = false;  // EGL_KHR_surfaceless_context: current without a surface
  bool mesa = false;            // Mesa's EGL: shares its GL dispatch with OSMesa (EglApi)
  ~Display() {
    if (handle != EGL_NO_DISPLAY) egl().Terminate(handle);
  }
};

namespace {

using Display = EglContext::Display;

// Initializes `display` and keeps it if it can render desktop OpenGL; otherwise terminates it.
std::shared_ptr<Display> try_display(EGLDisplay handle, std::string description, std::string* why) {
  if (handle == EGL_NO_DISPLAY) {
    *why += description + ": no display (" + egl_error_text() + "); ";
    return nullptr;
  }
  EGLint major = 0, minor = 0;
  if (egl().Initialize(handle, &major, &minor) != EGL_TRUE) {
    *why += description + ": eglInitialize failed (" + egl_error_text() + "); ";
    return nullptr;
  }
  auto display = std::make_shared<Display>();
  display->handle = handle;  // terminated by ~Display from here on
  display->description = std::move(description);
  const char* apis = egl().QueryString(handle, EGL_CLIENT_APIS);
  if (!has_extension(apis, "OpenGL") || !choose_config(handle, 0)) {
    *why += display->description + ": no desktop OpenGL configuration; ";
    return nullptr;
  }
  const char* vendor = egl().QueryString(handle, EGL_VENDOR);
  display->mesa = vendor != nullptr && std::strstr(vendor, "Mesa") != nullptr;
  display->surfaceless_ok =
      has_extension(egl().QueryString(handle, EGL_EXTENSIONS), "EGL_KHR_surfaceless_context");
  return display;
}

// A hardware EGL device (a GPU), or null. Mesa also lists a software device; the surfaceless
// platform below is that same llvmpipe, so software devices are left to it.
std::shared_ptr<Display> open_device_display(const char* client_extensions, std::string* why) {
  if (!has_extension(client_extensions, "EGL_EXT_device_enumeration") ||
      !has_extension(client_extensions, "EGL_EXT_platform_device")) {
    return nullptr;
  }
  auto query_devices =
      reinterpret_cast<PFNEGLQUERYDEVICESEXTPROC>(egl().GetProcAddress("eglQueryDevicesEXT"));
  auto query_device_string = reinterpret_cast<PFNEGLQUERYDEVICESTRINGEXTPROC>(
      egl().GetProcAddress("eglQueryDeviceStringEXT"));
  auto get_platform_display = reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(
      egl().GetProcAddress("eglGetPlatformDisplayEXT"));
  if (query_devices == nullptr || query_device_string == nullptr ||
      get_platform_display == nullptr) {
    return nullptr;
  }
  EGLDeviceEXT devices[kMaxDevices];
  EGLint count = 0;
  if (query_devices(kMaxDevices, devices, &count) != EGL_TRUE) return nullptr;
  for (EGLint i = 0; i < count; ++i) {
    if (has_extension(query_device_string(devices[i], EGL_EXTENSIONS),
                      "EGL_MESA_device_software")) {
      continue;
    }
    const char* file =
        has_extension(query_device_string(devices[i], EGL_EXTENSIONS), "EGL_EXT_device_drm")
            ? query_device_string(devices[i], EGL_DRM_DEVICE_FILE_EXT)
            : nullptr;
    std::string description = "EGL device " + std::to_string(i);
    if (file != nullptr) description += std::string(" (") + file + ")";
    auto display = try_display(get_platform_display(EGL_PLATFORM_DEVICE_EXT, devices[i], nullptr),
                               description, why);
    if (display) return display;
  }
  return nullptr;
}

// Mesa's surfaceless platform: no window system, no device file; llvmpipe without a GPU.
std::shared_ptr<Display> open_surfaceless_display(const char* client_extensions, std::string* why) {
  if (!has_extension(client_extensions, "EGL_MESA_platform_surfaceless")) {
    *why += "EGL_MESA_platform_surfaceless: not offered; ";
    return nullptr;
  }
  auto get_platform_display = reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(
      egl().GetProcAddress("eglGetPlatformDisplayEXT"));
  if (get_platform_display == nullptr) {
    *why += "eglGetPlatformDisplayEXT: missing; ";
    return nullptr;
  }
  return try_display(
      get_platform_display(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr),
      "surfaceless platform", why);
}

#if defined(__SANITIZE_ADDRESS__)
#define UAVSIM_EGL_PIN_DRIVER 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define UAVSIM_EGL_PIN_DRIVER 1
#endif
#endif

// Sanitizer builds only: Mesa's EGL unloads its DRI driver (llvmpipe's swrast_dri.so, or a GPU's)
// when the display is terminated, before LeakSanitizer's check at exit. The driver's process-lifetime
// allocations then show in frames of an "<unknown module>" that no suppression can name; keeping the
// driver mapped lets scripts/lsan.supp's `_dri.so` line suppress them, as for OSMesa.
void pin_dri_drivers() {
#ifdef UAVSIM_EGL_PIN_DRIVER
  dl_iterate_phdr(
      [](dl_phdr_info* info, size_t, void*) {
        const char* name = info->dlpi_name;
        if (name != nullptr && std::strstr(name, "_dri.so") != nullptr) {
          // RTLD_NOLOAD: only the mapped driver gains a reference, and NODELETE keeps it
          (void)dlopen(name, RTLD_NOW | RTLD_NOLOAD | RTLD_NODELETE);
        }
        return 0;
      },
      nullptr);
#endif
}

std::shared_ptr<Display> shared_display() {
  static std::mutex mutex;
  static std::weak_ptr<Display> shared;
  std::lock_guard<std::mutex> lock(mutex);
  if (auto display = shared.lock()) return display;
  // client extensions: queried on no display (EGL_EXT_client_extensions)
  const char* client_extensions = egl().QueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
  if (client_extensions == nullptr) {
    throw std::runtime_error("egl: no client extensions (" + egl_error_text() +
                             "): libEGL without a platform extension");
  }
  std::string why;
  std::shared_ptr<Display> display = open_device_display(client_extensions, &why);
  if (!display) display = open_surfaceless_display(client_extensions, &why);
  if (!display) throw std::runtime_error("egl: no display renders desktop OpenGL: " + why);
  pin_dri_drivers();
  shared = display;
  return display;
}

}  // namespace

EglContext::EglContext(int surface_width, int surface_height) : display_(shared_display()) {
  const EGLDisplay display = display_->handle;
  // eglBindAPI is per thread: desktop OpenGL (MuJoCo 2.2's renderer is fixed-function GL), not ES
  if (egl().BindAPI(EGL_OPENGL_API) != EGL_TRUE) {
    throw std::runtime_error("egl: eglBindAPI(EGL_OPENGL_API) failed (" + egl_error_text() + ")");
  }
  // a pbuffer as the default framebuffer where the display has one (every GPU driver and Mesa's
  // surfaceless platform do), else no surface at all (EGL_KHR_surfaceless_context)
  std::optional<EGLConfig> config = choose_config(display, EGL_PBUFFER_BIT);
  const bool pbuffer = config.has_value();
  if (!pbuffer) {
    if (!display_->surfaceless_ok) {
      throw std::runtime_error("egl: " + display_->description +
                               " has neither pbuffers nor EGL_KHR_surfaceless_context");
    }
    config = choose_config(display, 0);
  }
  config_ = *config;
  // no version or profile asked: the driver's compatibility context, which keeps the legacy GL
  // (display lists, fixed-function lighting) that mjr_* draws with; a core profile would lack it
  context_ = egl().CreateContext(display, *config, EGL_NO_CONTEXT, nullptr);
  if (context_ == EGL_NO_CONTEXT) {
    throw std::runtime_error("egl: eglCreateContext(desktop OpenGL) on " + display_->description +
                             " failed (" + egl_error_text() + ")");
  }
  surface_ = EGL_NO_SURFACE;
  if (pbuffer) {
    const EGLint attribs[] = {EGL_WIDTH, surface_width, EGL_HEIGHT, surface_height, EGL_NONE};
    surface_ = egl().CreatePbufferSurface(display, *config, attribs);
    if (surface_ == EGL_NO_SURFACE) {
      const std::string error = egl_error_text();
      egl().DestroyContext(display, context_);
      throw std::runtime_error("egl: eglCreatePbufferSurface on " + display_->description +
                               " failed (" + error + ")");
    }
  }
  if (!display_->mesa) publish_egl();
}

EglContext::~EglContext() {
  release();
  if (surface_ != EGL_NO_SURFACE) egl().DestroySurface(display_->handle, surface_);
  egl().DestroyContext(display_->handle, context_);
  // the thread's EGL state (bound API, error) is freed here unless another context is current
  if (egl().GetCurrentContext() == EGL_NO_CONTEXT) egl().ReleaseThread();
}

bool EglContext::make_current() {
  if (egl().GetCurrentContext() == context_) return true;
  if (egl().BindAPI(EGL_OPENGL_API) != EGL_TRUE) return false;
  return egl().MakeCurrent(display_->handle, surface_, surface_, context_) == EGL_TRUE;
}

void EglContext::release() {
  if (egl().GetCurrentContext() == context_) {
    egl().MakeCurrent(display_->handle, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
  }
}

std::string EglContext::detail() const {
  std::string text = display_->description;
  if (egl().GetCurrentContext() == context_) {
    // the renderer and version strings need the context current (as after make_current)
    auto get_string = reinterpret_cast<GlGetString>(egl().GetProcAddress("glGetString"));
    const unsigned char* renderer = get_string ? get_string(kGlRenderer) : nullptr;
    const unsigned char* version = get_string ? get_string(kGlVersion) : nullptr;
    if (renderer) text += std::string(", ") + reinterpret_cast<const char*>(renderer);
    if (version) text += std::string(", OpenGL ") + reinterpret_cast<const char*>(version);
  }
  return text;
}

}  // namespace uavsim::server::render
