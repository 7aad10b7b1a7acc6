#include "render/gl_context.hpp"

#include <stdexcept>
#include <string>

#include "render/osmesa_context.hpp"

namespace uavsim::server::render {

std::unique_ptr<GlContext> make_gl_context(std::string_view backend) {
  // one line per backend; the first is the default
  if (backend.empty() || backend == "osmesa") return std::make_unique<OsmesaContext>();
  throw std::invalid_argument("render: unknown GL backend '" + std::string(backend) +
                              "' (known: osmesa)");
}

}  // namespace uavsim::server::render
