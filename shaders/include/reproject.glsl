// Reprojection helpers. Pixel centres are at (x + 0.5, y + 0.5); motion
// vectors (after FrameConstants.motion scaling) point from the current pixel
// centre to its position in the previous frame: p_prev = p + mv.
#ifndef DN_REPROJECT_GLSL
#define DN_REPROJECT_GLSL

#include "inside.glsl"

// Minimum total weight of the accepted bilinear taps below which the history
// is treated as lost (a documented constant, not a tunable).
const float DN_MIN_TAP_WEIGHT = 1e-3;

// Motion below which a pixel counts as static (px per frame): its history is
// not clipped within its noise (svgf_reproject's clip_box) and its final
// output is stabilised by taa_static_alpha (svgf_remodulate).
const float DN_STATIC_MOTION = 0.05;

// A still pixel (svgf converge_still, motion below a tenth of
// DN_STATIC_MOTION) keeps the plain running mean of its own unfiltered
// samples, of up to DN_STILL_MAX_SAMPLES (then an exponential average).
const float DN_STILL_MOTION = 0.1 * DN_STATIC_MOTION;
const float DN_STILL_MAX_SAMPLES = 65536.0;
bool dn_is_still(vec2 mv) { return length(mv) < DN_STILL_MOTION; }
// The weight of a still pixel's running mean of n samples as its target
// (svgf_remodulate), and against reflect_median's median: 0 below
// DN_STILL_MIN_SAMPLES (at 8, on dnrender's still scenes the capped filter's
// error had grown above the plain mean's by then), 1/4 there, rising over
// DN_STILL_RAMP samples to 1 from 7 on, so the output does not jump.
const float DN_STILL_MIN_SAMPLES = 4.0;
// From how many samples svgf_reproject hands a still pixel's running mean to
// the filter instead of its history: from 4 the error of a flat still view
// tripled at the switch (the filtered history of a few frames is the less
// noisy); from 8 and from 12 every count of dnrender's still scenes fell.
const float DN_STILL_FILTER_FROM = 8.0;
// Whether the still running means are kept and used (svgf converge_still > 0),
// in a pass with the CONVERGE_STILL constant.
#define DN_CONVERGING_STILL (CONVERGE_STILL && DN_PARAM_VALUE(svgf, converge_still) > 0.0)
const float DN_STILL_RAMP = 4.0;
float dn_still_weight(float n) {
  return n >= DN_STILL_MIN_SAMPLES ? clamp((n - DN_STILL_MIN_SAMPLES + 1.0) / DN_STILL_RAMP, 0.0, 1.0) : 0.0;
}

// 1 for a static pixel, falling linearly to 0 at DN_STATIC_MOTION.
float dn_stillness(vec2 mv) { return clamp(1.0 - length(mv) / DN_STATIC_MOTION, 0.0, 1.0); }

vec2 dn_previous_position(uint pixel, uint width, vec2 motion_px) {
  return vec2(float(pixel % width), float(pixel / width)) + 0.5 + motion_px;
}

// Bilinear footprint of a position in pixel units: the top-left tap and the
// weights of taps (0,0), (1,0), (0,1), (1,1). Returns false when the position
// is so far outside the image that no tap can be inside (this also keeps the
// float -> int conversion in range).
bool dn_bilinear_footprint(vec2 p, uvec2 size, out ivec2 origin, out vec4 weights) {
  vec2 f = p - 0.5;
  if (!(f.x > -1.0 && f.y > -1.0 && f.x < float(size.x) && f.y < float(size.y))) {
    origin = ivec2(0);
    weights = vec4(0.0);
    return false;
  }
  vec2 base = floor(f);
  vec2 t = f - base;
  origin = ivec2(base);
  weights = vec4((1.0 - t.x) * (1.0 - t.y), t.x * (1.0 - t.y), (1.0 - t.x) * t.y, t.x * t.y);
  return true;
}

// Falcor's SVGF consistency test of a previous pixel (depth z_prev, normal
// n_prev) against the current pixel (z, n, and its geometry gradients grad:
// depth, normal distance; svgf.glsl's dn_svgf_gradients): the same surface
// when the depth and normal differences are within 10 and 16 gradients
// (dn_same_depth: the depth half alone).
bool dn_same_depth(float z, float grad_z, float z_other) { return !(abs(z - z_other) / (grad_z + 0.01) > 10.0); }
bool dn_same_surface(float z, vec3 n, vec2 grad, float z_prev, vec3 n_prev) {
  return dn_same_depth(z, grad.x, z_prev) && !(distance(n, n_prev) / (grad.y + 0.01) > 16.0);
}

#endif
