#include "render/plane_grid.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace uavsim::server::render {

int plane_grid_quads_per_side(double half_m, double spacing_m) {
  // an infinite side, or a size MuJoCo would not compile (NaN, infinite): the cap
  if (!(half_m > 0.0) || !std::isfinite(half_m)) return kMaxPlaneGridQuads;
  const double finest = half_m / (kMaxPlaneGridQuads - 2);
  const double spacing = spacing_m > finest ? spacing_m : finest;  // a NaN spacing is the finest
  // half_m / spacing is at most kMaxPlaneGridQuads - 2 here, so the cast is defined
  const int n = static_cast<int>(std::floor(half_m / spacing));
  return n - n % 2 + 2;
}

std::vector<std::string> dense_plane_grid_warnings(const mjModel* m) {
  std::vector<std::string> lines;
  for (int g = 0; g < m->ngeom; ++g) {
    if (m->geom_type[g] != mjGEOM_PLANE) continue;
    const mjtNum* size = m->geom_size + 3 * g;
    const int nx = plane_grid_quads_per_side(size[0], size[2]);
    const int ny = plane_grid_quads_per_side(size[1], size[2]);
    if (std::max(nx, ny) <= kDensePlaneGridQuads) continue;
    const char* name = mj_id2name(m, mjOBJ_GEOM, g);
    std::ostringstream line;
    line << "plane geom ";
    if (name) {
      line << "'" << name << "'";
    } else {
      line << "#" << g;
    }
    line << " is drawn as " << nx << " x " << ny << " quads in every camera frame";
    if (size[0] > 0.0 && size[1] > 0.0) {
      // the spacing that brings the longer side to 20 quads
      const double coarse_m = std::max(size[0], size[1]) / 20.0;
      line << " (its size's third value, " << size[2] << " m, is the render grid's spacing): under "
           << "directional lights a spacing of " << coarse_m
           << " m draws it the same at a fraction of the cost";
    } else {
      line << " (an infinite plane always is): give it a finite size and a coarse grid spacing";
    }
    lines.push_back(line.str());
  }
  return lines;
}

}  // namespace uavsim::server::render
