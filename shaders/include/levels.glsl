// Grids at reduced resolution. Level 0 is the full grid; level L + 1 reduces
// level L by `factor` per axis, rounding up: size_{L+1} = ceil(size_L / factor)
// (1/2 and 1/3 resolution are level 1 of factor 2 and 3; a 3x3 pyramid runs
// down to 1x1). Coarse pixel P covers the fine pixels P·factor + [0, factor)²
// that lie inside the finer level: the last row and column of a level whose
// finer size is not divisible cover a partial block. A packed pyramid stores
// all levels in one buffer, level after level, each row-major.
// Mirrors dn::gpu::level_size / level_offset (server/gpu/levels.hpp).
#ifndef DN_LEVELS_GLSL
#define DN_LEVELS_GLSL

uvec2 dn_level_size(uvec2 size0, uint factor, uint level) {
  uvec2 s = size0;
  for (uint l = 0u; l < level; ++l) s = (s + factor - 1u) / factor;
  return s;
}

// Elements before level `level` in a packed pyramid.
uint dn_level_offset(uvec2 size0, uint factor, uint level) {
  uvec2 s = size0;
  uint offset = 0u;
  for (uint l = 0u; l < level; ++l) {
    offset += s.x * s.y;
    s = (s + factor - 1u) / factor;
  }
  return offset;
}

// The coarse pixel covering fine pixel p, and the first fine pixel of coarse pixel p.
uvec2 dn_level_parent(uvec2 p, uint factor) { return p / factor; }
uvec2 dn_level_first_child(uvec2 p, uint factor) { return p * factor; }

#endif
