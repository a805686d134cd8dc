// Grids at reduced resolution (shaders/include/levels.glsl is the GLSL
// side). Level 0 is the full grid; level L + 1 reduces level L by `factor`
// per axis, rounding up, so 1/2 and 1/3 resolution are level 1 of factor 2
// and 3, and a 3x3 pyramid (progressive SVGF's hole filling) runs down to
// 1x1. A packed pyramid keeps every level in one buffer, level after level.
#pragma once

#include <cstdint>

namespace dn::gpu {

struct Extent {
  uint32_t width = 0;
  uint32_t height = 0;
  constexpr uint64_t pixels() const { return uint64_t{width} * height; }
  constexpr bool operator==(const Extent&) const = default;
};

// Size of level `level` (factor >= 2; factor 1 leaves the size unchanged).
constexpr Extent level_size(uint32_t width, uint32_t height, uint32_t factor, uint32_t level) {
  Extent e{width, height};
  if (factor < 2) return e;
  // ceil(ceil(w / f) / f) = ceil(w / f²): iterating avoids overflowing f^level.
  for (uint32_t l = 0; l < level && (e.width > 1 || e.height > 1); ++l)
    e = {(e.width + factor - 1) / factor, (e.height + factor - 1) / factor};
  return e;
}

// Levels of the pyramid down to 1x1, that level included (1 for a 1x1 grid,
// 0 for an empty one).
constexpr uint32_t level_count(uint32_t width, uint32_t height, uint32_t factor) {
  if (width == 0 || height == 0) return 0;
  if (factor < 2) return 1;
  uint32_t n = 1;
  for (Extent e{width, height}; e.width > 1 || e.height > 1; ++n) e = level_size(e.width, e.height, factor, 1);
  return n;
}

// Pixels before level `level` in a packed pyramid (its element offset).
constexpr uint64_t level_offset(uint32_t width, uint32_t height, uint32_t factor, uint32_t level) {
  uint64_t offset = 0;
  for (uint32_t l = 0; l < level; ++l) offset += level_size(width, height, factor, l).pixels();
  return offset;
}

// Pixels of a packed pyramid with all level_count() levels.
constexpr uint64_t pyramid_pixels(uint32_t width, uint32_t height, uint32_t factor) {
  return level_offset(width, height, factor, level_count(width, height, factor));
}

}  // namespace dn::gpu
