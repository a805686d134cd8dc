#version 450
// Test kernel for levels.glsl (tests/gpu/levels_test.cpp): one level of a
// packed pyramid from the next finer one, each coarse pixel the mean of the
// valid pixels of its factor x factor block; a coarse pixel without any
// valid child is invalid (value 0), so no-data pixels never contribute. The
// hole-filling pull of progressive SVGF. Not used by any pipeline.
//
// Push constants (grid2d.glsl): size = the level written, source = the level
// read; args = (level written, factor, level-0 width, level-0 height).
#extension GL_GOOGLE_include_directive : require
#include "grid2d.glsl"
#include "levels.glsl"
#include "pass.glsl"
#include "generated/passes/pyramid_probe.pass"

void main() {
  const uvec2 p = dn_pixel();
  if (!dn_in_grid(p)) return;
  const uint level = dn_arg_level();
  const uint factor = dn_arg_factor();
  const uvec2 size0 = uvec2(dn_arg_width0(), dn_arg_height0());
  const uint fine = dn_level_offset(size0, factor, level - 1u);
  const uint coarse = dn_level_offset(size0, factor, level);
  const uvec2 first = dn_level_first_child(p, factor);
  const uvec2 end = min(first + factor, dn_grid.source);
  vec4 sum = vec4(0.0);
  uint n = 0u;
  for (uint y = first.y; y < end.y; ++y) {
    for (uint x = first.x; x < end.x; ++x) {
      const uint i = fine + dn_grid_index(uvec2(x, y), dn_grid.source);
      if (valid.data[i] == 0u) continue;
      sum += values.data[i];
      ++n;
    }
  }
  const uint o = coarse + dn_grid_index(p, dn_grid.size);
  values.data[o] = n > 0u ? sum / float(n) : vec4(0.0);
  valid.data[o] = n > 0u ? 1u : 0u;
}
