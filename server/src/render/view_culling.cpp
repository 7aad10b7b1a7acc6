#include "render/view_culling.hpp"

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>

namespace uavsim::server::render {

namespace {

// Bounding radius of a model geom as drawn, or -1 for what always stays in the scene.
double drawn_radius(const mjModel* m, const mjvGeom& g) {
  if (g.objtype != mjOBJ_GEOM || g.objid < 0 || g.objid >= m->ngeom) return -1.0;  // decor, skin
  if (g.type == mjGEOM_PLANE || g.type == mjGEOM_HFIELD) return -1.0;  // unbounded or not centred
  const double r = m->geom_rbound[g.objid];
  return std::isfinite(r) && r > 0.0 ? r : -1.0;
}

}  // namespace

int remove_geoms_outside_view(const mjModel* m, int width_px, int height_px, mjvScene* scn) {
  if (width_px <= 0 || height_px <= 0) return 0;
  // the camera mjr_render draws with (the average of the two eyes, which for mono are the same)
  const mjvGLCamera cam = mjv_averageCamera(scn->camera, scn->camera + 1);
  const double near = cam.frustum_near;
  const double far = cam.frustum_far;
  if (!(near > 0.0) || !(far > near)) return 0;
  const Eigen::Vector3d pos(cam.pos[0], cam.pos[1], cam.pos[2]);
  const Eigen::Vector3d forward =
      Eigen::Vector3d(cam.forward[0], cam.forward[1], cam.forward[2]).normalized();
  const Eigen::Vector3d up = Eigen::Vector3d(cam.up[0], cam.up[1], cam.up[2]).normalized();
  const Eigen::Vector3d right = forward.cross(up);
  // the frustum's extent on the near plane, as mjr_render sets it up (glFrustum)
  const double half_width = 0.5 * width_px / height_px * (cam.frustum_top - cam.frustum_bottom);
  const double left = cam.frustum_center - half_width;
  const double rightx = cam.frustum_center + half_width;
  const double bottom = cam.frustum_bottom;
  const double top = cam.frustum_top;
  // inward unit normals of the four side planes (through the eye) in the camera's (right, up,
  // forward)
  const Eigen::Vector3d sides[4] = {
      Eigen::Vector3d(near, 0.0, -left).normalized(),    // left: x near - z left >= 0 inside
      Eigen::Vector3d(-near, 0.0, rightx).normalized(),  // right
      Eigen::Vector3d(0.0, near, -bottom).normalized(),  // bottom
      Eigen::Vector3d(0.0, -near, top).normalized(),     // top
  };

  int kept = 0;
  for (int i = 0; i < scn->ngeom; ++i) {
    const mjvGeom& g = scn->geoms[i];
    const double r = drawn_radius(m, g);
    bool outside = false;
    if (r > 0.0) {
      const Eigen::Vector3d d = Eigen::Vector3d(g.pos[0], g.pos[1], g.pos[2]) - pos;
      const Eigen::Vector3d v(d.dot(right), d.dot(up), d.dot(forward));
      outside = v.z() + r < near || v.z() - r > far;
      for (const Eigen::Vector3d& n : sides) outside = outside || n.dot(v) < -r;
    }
    if (!outside) scn->geoms[kept++] = g;
  }
  const int removed = scn->ngeom - kept;
  scn->ngeom = kept;
  return removed;
}

}  // namespace uavsim::server::render
