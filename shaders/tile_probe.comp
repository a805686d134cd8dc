#version 450
// Test kernel for tile.glsl (tests/gpu/tile_test.cpp): a disc gather of
// radius R <= APRON from a shared-memory tile, two ways: a Gaussian over the
// clamped tile (edge replication) and a box mean over the taps inside the
// grid only. Not used by any pipeline.
//
// Push constants (grid2d.glsl): size = grid, args.x = R, args.y = sigma (float bits).
#extension GL_GOOGLE_include_directive : require
#include "grid2d.glsl"
#include "pass.glsl"
#include "generated/passes/tile_probe.pass"

#define DN_TILE_APRON APRON
#include "tile.glsl"

vec4 dn_tile_fetch(ivec2 p) { return source.data[dn_grid_index(uvec2(p), dn_grid.size)]; }

void main() {
  dn_tile_load(dn_grid.size);
  const uvec2 p = dn_pixel();
  if (!dn_in_grid(p)) return;
  const int r = int(min(dn_arg_radius(), APRON));
  const float sigma = dn_arg_sigma();
  vec4 gauss = vec4(0.0), box = vec4(0.0);
  float gauss_w = 0.0, box_n = 0.0;
  for (int dy = -r; dy <= r; ++dy) {
    for (int dx = -r; dx <= r; ++dx) {
      if (dx * dx + dy * dy > r * r) continue;
      const ivec2 d = ivec2(dx, dy);
      const vec4 v = dn_tile_at(d);
      const float w = exp(-float(dx * dx + dy * dy) / (2.0 * sigma * sigma));
      gauss += w * v;
      gauss_w += w;
      if (dn_tile_inside(d, dn_grid.size)) {
        box += v;
        box_n += 1.0;
      }
    }
  }
  const uint i = dn_grid_index(p, dn_grid.size);
  clamped.data[i] = gauss / gauss_w;
  inside.data[i] = box / box_n;
}
