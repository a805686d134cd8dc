#version 450
// stat_filter_tiled: stat_filter (see there and docs/pipelines.md, "stat")
// with the disc read from a shared-memory tile: each 8x8 workgroup loads the
// (8 + 2 APRON)^2 pixels around its block once (theta,
// variance, the value (dn_stat_value), sanitized albedo and normal: 80 B each, 32000 B
// in all, within lavapipe's 32 KiB) instead of every invocation loading its
// own taps. It measured 1.5x faster on lavapipe at radius 6
// (bench/stat_gather_bench, docs/results.md); the host uses it when the
// radius is at most the apron and the width is even (the output is written in
// pixel pairs, each pair within one workgroup). Same decisions and sums as
// stat_filter, in the same order.
//
// Resources: stat_filter_tiled.pass (binding 0 FrameConstants; push
// constants: grid2d.glsl, size = source = the session's grid).
#extension GL_GOOGLE_include_directive : require
#include "grid2d.glsl"
#include "frame.glsl"
#include "plane.glsl"
#include "sanitize.glsl"
#include "pass.glsl"
#include "generated/passes/stat_filter_tiled.pass"

#include "stat_filter_io.glsl"
#include "stat_class.glsl"
#include "stat_gather.glsl"

struct Tap {
  vec4 theta, variance, raw, albedo, normal;
};
#define DN_TILE_APRON APRON
#define DN_TILE_T Tap
#include "tile.glsl"

Tap dn_tile_fetch(ivec2 p) {
  uint i = dn_grid_index(uvec2(p), dn_grid.size);
  return Tap(theta_at(i), variance_at(i), vec4(dn_stat_value(i), 0.0),
             vec4(dn_sanitize_albedo(DN_LOAD3(albedo, i)), 0.0),
             vec4(dn_sanitize_normal(DN_LOAD3(normal, i)), 0.0));
}

vec3 filter_pixel() {
  Tap c = dn_tile_at(ivec2(0));
  vec3 raw_p = c.raw.rgb;
  if (!(c.theta.w > 0.0) || c.variance.w == DN_STAT_KEPT) return dn_stat_remodulate(raw_p, dn_grid_index(dn_pixel(), dn_grid.size));
  int r = int(DN_PARAM_VALUE(stat, radius));
  DnStatKernel k = dn_stat_kernel_from_parameters();
  k.asymmetric = k.asymmetric || c.variance.w == DN_STAT_MOVING;
  dn_stat_narrow_still(k, r, c.theta, c.variance.w);
  vec3 sum = vec3(0.0);  // of weight * (raw_q - raw_p)
  float weight_sum = 1.0;
  for (int dy = -r; dy <= r; ++dy)
    for (int dx = -r; dx <= r; ++dx) {
      int d2xy = dx * dx + dy * dy;
      ivec2 offset = ivec2(dx, dy);
      if (d2xy > r * r || d2xy == 0 || !dn_tile_inside(offset, dn_grid.size)) continue;
      Tap q = dn_tile_at(offset);
      bool still = c.variance.w == DN_STAT_TESTED && q.variance.w == DN_STAT_TESTED;
      float m = dn_stat_membership(c.theta, c.variance.rgb, q.theta, q.variance.rgb, k, still);
      if (m == 0.0) continue;
      float w = m * dn_stat_base_weight(d2xy, c.albedo.rgb - q.albedo.rgb, c.normal.rgb - q.normal.rgb, k);
      sum += w * (q.raw.rgb - raw_p);
      weight_sum += w;
    }
  return dn_stat_remodulate(raw_p + sum / weight_sum, dn_grid_index(dn_pixel(), dn_grid.size));
}

void main() {
  dn_tile_load(dn_grid.size);
  const uvec2 p = dn_pixel();
  const bool inside = dn_in_grid(p);
  vec3 result_p = inside ? filter_pixel() : vec3(0.0);
  // Pairs (even x, x + 1) are stored by the even one: the odd one hands its
  // result over through the tile, which nobody reads any more.
  barrier();
  dn_tile[gl_LocalInvocationIndex].raw = vec4(result_p, 0.0);
  barrier();
  if (inside && (p.x & 1u) == 0u) {
    vec3 b = dn_tile[gl_LocalInvocationIndex + 1u].raw.rgb;
    DN_STORE_RGB_PAIR(result, dn_grid_index(p, dn_grid.size) / 2u, result_p, b, true)
  }
}
