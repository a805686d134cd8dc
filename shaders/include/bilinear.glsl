// Bilinear fetch of a buffer at a continuous position in pixels (pixel
// centres at x + 0.5): the four taps around it, each dropped when it lies
// outside the grid, fails a validity test or has weight 0 (so a NaN in a
// dropped tap never leaks), the remaining weights renormalised. Beyond the
// outer pixel centres this reads as clamp-to-edge; with no valid tap the
// result is 0 with total weight 0, which the caller tests (e.g. against
// reproject.glsl's DN_MIN_TAP_WEIGHT).
//
// The footprint is reproject.glsl's dn_bilinear_footprint, reused as it is
// (svgf_reproject's output cannot change).
#ifndef DN_BILINEAR_GLSL
#define DN_BILINEAR_GLSL

#include "reproject.glsl"

// Validity test that accepts every tap (for DN_BILINEAR_FETCH_FN).
bool dn_bilinear_any(uint index) { return true; }

// Defines `vec4 NAME(vec2 p, uvec2 size, out float total)`: the fetch from
// BUF (a buffer block { vec4 data[]; }, row-major, size.x wide) with taps
// whose index fails `bool VALID(uint index)` dropped; total is the sum of
// the kept weights before renormalisation. A macro because GLSL cannot pass
// buffers to functions.
#define DN_BILINEAR_FETCH_FN(NAME, BUF, VALID)                     \
  vec4 NAME(vec2 p, uvec2 size, out float total) {                 \
    ivec2 origin;                                                  \
    vec4 w;                                                        \
    vec4 sum = vec4(0.0);                                          \
    total = 0.0;                                                   \
    if (dn_bilinear_footprint(p, size, origin, w)) {               \
      for (int k = 0; k < 4; ++k) {                                \
        ivec2 q = origin + ivec2(k & 1, k >> 1);                   \
        if (!(w[k] > 0.0) || !dn_inside(q, size)) continue;        \
        uint i = uint(q.y) * size.x + uint(q.x);                   \
        if (!VALID(i)) continue;                                   \
        sum += w[k] * BUF.data[i];                                 \
        total += w[k];                                             \
      }                                                            \
    }                                                              \
    return total > 0.0 ? sum / total : vec4(0.0);                  \
  }

#endif
