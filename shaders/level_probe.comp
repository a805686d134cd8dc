#version 450
// Test kernel for buffers at reduced resolution in a pass graph
// (tests/pipelines/graph_levels_test.cpp), with pyramid_probe between its two
// modes. fill (grid = the full resolution): level 0 of the pyramid from the
// radiance plane; a pixel whose red is negative is no-data. read (grid =
// the full resolution, args = (level, factor, width, height)): each output
// pixel takes the value of its ancestor at `level` (nearest), 0 where that
// ancestor has no data. Not used by any pipeline.
#extension GL_GOOGLE_include_directive : require
#include "grid2d.glsl"
#include "levels.glsl"
#include "plane.glsl"
#include "pass.glsl"
#include "generated/passes/level_probe.pass"

void main() {
  const uvec2 p = dn_pixel();
  if (!dn_in_grid(p)) return;
  const uint i = dn_grid_index(p, dn_grid.size);
  if (MODE == DN_MODE_fill) {
    const vec3 c = DN_LOAD3(radiance, i);
    values.data[i] = vec4(c, 0.0);
    valid.data[i] = c.r >= 0.0 ? 1u : 0u;
    return;
  }
  const uint level = dn_arg_level(), factor = dn_arg_factor();
  const uvec2 size0 = uvec2(dn_arg_width0(), dn_arg_height0());
  uvec2 q = p;
  for (uint l = 0u; l < level; ++l) q /= factor;
  const uint a = dn_level_offset(size0, factor, level) + dn_grid_index(q, dn_level_size(size0, factor, level));
  const vec3 c = valid.data[a] != 0u ? values.data[a].rgb : vec3(0.0);
  for (uint k = 0u; k < 3u; ++k) result.data[3u * i + k] = floatBitsToUint(c[k]);
}
