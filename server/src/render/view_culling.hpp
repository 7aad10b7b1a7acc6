// Geoms a camera cannot see, taken out of its scene before MuJoCo draws it. MuJoCo 2.2 sends every
// geom of the scene through the GL pipeline, where those outside the view are clipped only after
// their vertices were transformed and lit: on a CPU renderer (Mesa's llvmpipe) that vertex work is
// a large part of a small frame's cost, for the other vehicles, balloons and poles behind or beside
// a camera. A geom whose bounding sphere lies wholly outside the view frustum draws no pixel, so
// taking it out leaves the frame as it was — as long as nothing off screen shows in it: not with
// shadows or reflections, which draw the scene from other viewpoints (the caller keeps every geom
// then).
#pragma once

#include <mujoco/mujoco.h>

namespace uavsim::server::render {

// Removes from `scn` (as mjv_updateScene left it for one camera, mono) the model geoms whose
// bounding sphere (the model's geom_rbound around the geom's position) lies wholly outside the
// frustum that mjr_render draws into a viewport of width_px x height_px, keeping the others in
// their order. Planes, height fields, decor (sites, tendons, labels) and skins always stay. Returns
// how many were removed.
int remove_geoms_outside_view(const mjModel* m, int width_px, int height_px, mjvScene* scn);

}  // namespace uavsim::server::render
