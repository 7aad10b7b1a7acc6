// What a world's planes cost every camera frame. MuJoCo draws a plane as a grid of quads whose
// spacing is the plane's third size value, so that per-vertex lighting can vary across it; a grid
// of up to 200 x 200 quads (160000 vertices) is drawn in every frame of every camera. On a CPU
// renderer (Mesa's llvmpipe) that vertex work was most of a 384 x 216 frame's time. Under
// directional lights only (a sun, MuJoCo's headlight) a coarse grid shades the plane as the finest
// one does (tests/server/render/ground_grid_test.cpp), so the server warns about dense grids at
// start-up.
#pragma once

#include <mujoco/mujoco.h>

#include <string>
#include <vector>

namespace uavsim::server::render {

// MuJoCo's cap on a plane's grid: quads per side.
constexpr int kMaxPlaneGridQuads = 200;
// More quads per side than this in a rendered world gets a start-up warning (64 x 64 = 4096 quads).
constexpr int kDensePlaneGridQuads = 64;

// Quads per side MuJoCo's render context draws for one side of a plane: `half_m` its half-size
// along that side (0: infinite), `spacing_m` its third size value (the rule of MuJoCo 2.2's render
// context: a spacing of at least half_m / 198, an even count, plus two pads; an infinite side gets
// the cap).
int plane_grid_quads_per_side(double half_m, double spacing_m);

// One line per plane geom drawn with more than kDensePlaneGridQuads quads per side: its name, its
// grid and what to change. Empty when every plane is coarse.
std::vector<std::string> dense_plane_grid_warnings(const mjModel* m);

}  // namespace uavsim::server::render
