#include "render/gl_context.hpp"

#include <stdexcept>
#include <string>

#include "render/egl_context.hpp"
#include "render/osmesa_context.hpp"

namespace uavsim::server::render {

std::unique_ptr<GlContext> make_gl_context(std::string_view backend, std::string* fallback_reason) {
  if (backend.empty() || backend == "osmesa") return std::make_unique<OsmesaContext>();
  if (backend == "egl") return std::make_unique<EglContext>();
  if (backend == "auto") {
    try {
      return std::make_unique<EglContext>();
    } catch (const std::runtime_error& e) {
      if (fallback_reason != nullptr) *fallback_reason = e.what();
      return std::make_unique<OsmesaContext>();
    }
  }
  throw std::invalid_argument("render: unknown GL backend '" + std::string(backend) +
                              "' (known: " + kGlBackendNames + ")");
}

}  // namespace uavsim::server::render
